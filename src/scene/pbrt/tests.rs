use super::lexer::{Lexer, TokenKind};
use super::*;
use crate::math::{Vec2, Vec3};
use crate::settings::Value;
use glam::{Mat4, Vec4};
use std::collections::BTreeMap;
use std::io::{Error as IoError, ErrorKind};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// In-memory files; every other path is not found.
#[derive(Default)]
struct Files(BTreeMap<PathBuf, Vec<u8>>);

impl Files {
    fn with(mut self, path: &str, text: impl AsRef<[u8]>) -> Self {
        self.0.insert(PathBuf::from(path), text.as_ref().to_vec());
        self
    }
}

impl crate::scene::mesh::FileSource for Files {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        self.0
            .get(path)
            .cloned()
            .ok_or_else(|| IoError::new(ErrorKind::NotFound, "no such file"))
    }
}

/// A camera-less header that lets a test start in the world block.
const WORLD: &str = "WorldBegin\n";

fn parse(text: &str) -> PbrtScene {
    parse_with(text, Files::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn parse_with(text: &str, files: Files) -> Result<PbrtScene> {
    let files = files.with("scene/main.pbrt", text);
    load_from(Path::new("scene/main.pbrt"), &files)
}

/// The error's message, checked to be one line starting with `place`.
fn error(text: &str, place: &str) -> String {
    error_with(text, Files::default(), place)
}

fn error_with(text: &str, files: Files, place: &str) -> String {
    let e = parse_with(text, files)
        .expect_err("the scene should not load")
        .to_string();
    assert!(e.starts_with(place), "'{e}' does not start with '{place}'");
    assert!(!e.contains('\n'), "'{e}' is not one line");
    e
}

fn assert_mat(a: Mat4, b: Mat4) {
    assert!(a.abs_diff_eq(b, 1e-5), "\n{a:?}\n!=\n{b:?}");
}

fn point(m: Mat4, p: Vec3) -> Vec3 {
    m.transform_point3(p)
}

fn assert_vec(a: Vec3, b: Vec3) {
    assert!(a.abs_diff_eq(b, 1e-5), "{a} != {b}");
}

// ---- tokenizer --------------------------------------------------------------

fn tokens(text: &str) -> Vec<(TokenKind, u32, u32)> {
    let mut lx = Lexer::new(Arc::new(PathBuf::from("t.pbrt")), text.as_bytes().to_vec()).unwrap();
    let mut out = vec![];
    while let Some(t) = lx.next_token().unwrap() {
        out.push((t.kind, t.loc.line, t.loc.col));
    }
    out
}

fn num(v: f64) -> TokenKind {
    TokenKind::Num { value: v, int: None }
}

fn int(i: i64) -> TokenKind {
    TokenKind::Num {
        value: i as f64,
        int: Some(i),
    }
}

fn word(w: &str) -> TokenKind {
    TokenKind::Word(w.into())
}

#[test]
fn tokens_carry_line_and_column() {
    let text = "# a comment\nShape \"sphere\" \"float radius\" [ 2.5 ]# tail\n\t  Translate -1 +2 .5e1\n\"é\" x[1]\r\n";
    assert_eq!(
        tokens(text),
        vec![
            (word("Shape"), 2, 1),
            (TokenKind::Str("sphere".into()), 2, 7),
            (TokenKind::Str("float radius".into()), 2, 16),
            (TokenKind::Open, 2, 31),
            (num(2.5), 2, 33),
            (TokenKind::Close, 2, 37),
            (word("Translate"), 3, 4),
            (int(-1), 3, 14),
            (int(2), 3, 17),
            (num(5.0), 3, 20),
            (TokenKind::Str("é".into()), 4, 1),
            // Columns count characters: "é" is one.
            (word("x"), 4, 5),
            (TokenKind::Open, 4, 6),
            (int(1), 4, 7),
            (TokenKind::Close, 4, 8),
        ]
    );
}

#[test]
fn tokens_strings_escapes_and_malformed_numbers() {
    assert_eq!(
        tokens(r#""a\"b\\c\n" 1.2.3 inf 1e999 -"#),
        vec![
            (TokenKind::Str("a\"b\\c\n".into()), 1, 1),
            (word("1.2.3"), 1, 13),
            (word("inf"), 1, 19),
            (word("1e999"), 1, 23),
            (word("-"), 1, 29),
        ]
    );
    // A word runs up to a quote or bracket.
    assert_eq!(
        tokens("ab\"c\"]"),
        vec![
            (word("ab"), 1, 1),
            (TokenKind::Str("c".into()), 1, 3),
            (TokenKind::Close, 1, 6)
        ]
    );
}

fn lex_error(text: &[u8]) -> String {
    let mut lx = match Lexer::new(Arc::new(PathBuf::from("t.pbrt")), text.to_vec()) {
        Ok(lx) => lx,
        Err(e) => return e.to_string(),
    };
    loop {
        match lx.next_token() {
            Ok(Some(_)) => {}
            Ok(None) => panic!("no error"),
            Err(e) => return e.to_string(),
        }
    }
}

#[test]
fn tokenizer_errors_name_the_place() {
    assert_eq!(
        lex_error(b"Shape \"sphere\n\"x\""),
        "t.pbrt:1:7: unterminated string: a string must end on the line it starts"
    );
    assert_eq!(
        lex_error(b"\n  \"abc"),
        "t.pbrt:2:3: unterminated string: the file ends inside it"
    );
    assert_eq!(lex_error(b"\"a\\qb\""), "t.pbrt:1:4: unknown escape '\\q' in a string");
    assert_eq!(lex_error(b"ok\n ab\xff"), "t.pbrt:2:4: the file is not UTF-8 text");
    assert!(lex_error(b"\xff\xfeS\0").contains("UTF-16"));
}

// ---- directives ---------------------------------------------------------------

#[test]
fn every_directive_is_read() {
    let files = Files::default()
        .with("scene/inc/geometry.pbrt", "Shape \"sphere\" \"float radius\" 3\n")
        .with(
            "scene/imported.pbrt",
            "Material \"conductor\"\nShape \"disk\"\nReverseOrientation\n",
        );
    let text = r#"
Option "disablepixeljitter" true
ColorSpace "srgb"
LookAt 0 0 -5  0 0 0  0 1 0
Camera "perspective" "float fov" 45 "float screenwindow" [-1 1 -0.5 0.5]
Film "rgb" "integer xresolution" 64 "integer yresolution" [32] "float cropwindow" [0 1 0 0.5]
    "string filename" "out.exr"
Sampler "independent" "integer pixelsamples" 16
PixelFilter "box"
Integrator "sppm" "integer iterations" 8 "float radius" 0.1
Accelerator "bvh"
TransformTimes 0 1
WorldBegin
Attribute "shape" "float radius" 2
Texture "checks" "spectrum" "checkerboard" "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]
Texture "rough" "float" "constant" "float value" 0.2
MakeNamedMaterial "red" "string type" "diffuse" "texture reflectance" "checks"
Material "dielectric" "float eta" 1.5
LightSource "point" "rgb I" [1 2 3] "point3 from" [0 4 0]
MakeNamedMedium "fog" "string type" "homogeneous"
AttributeBegin
  MediumInterface "fog" ""
  CoordinateSystem "here"
  Identity
  Translate 1 2 3
  Rotate 90 0 0 1
  Scale 2 2 2
  ConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1]
  CoordSysTransform "here"
  NamedMaterial "red"
  AreaLightSource "diffuse" "blackbody L" 6500 "float scale" 2
  ReverseOrientation
  Shape "sphere"
AttributeEnd
ObjectBegin "thing"
  Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0]
ObjectEnd
Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 7 1]
ObjectInstance "thing"
Include "inc/geometry.pbrt"
Import "imported.pbrt"
Shape "bilinearmesh" "point3 P" [0 0 0 1 0 0 0 1 0 1 1 0]
"#;
    let s = parse_with(text, files).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.options.len(), 1);
    assert_eq!(s.options[0].name, "disablepixeljitter");
    assert_eq!(s.options[0].value, "true");
    assert_eq!(s.camera.ty, "perspective");
    assert_eq!(s.camera.params.get_float("fov", 90.0).unwrap(), 45.0);
    assert_eq!(s.camera.params.get_floats("screenwindow"), &[-1.0, 1.0, -0.5, 0.5]);
    assert_eq!(s.film.params.get_int("xresolution", 1280).unwrap(), 64);
    assert_eq!(s.film.params.get_int("yresolution", 720).unwrap(), 32);
    assert_eq!(s.film.params.get_floats("cropwindow"), &[0.0, 1.0, 0.0, 0.5]);
    assert_eq!(s.sampler.ty, "independent");
    assert_eq!(s.filter.ty, "box");
    assert_eq!(s.integrator.ty, "sppm");
    assert_eq!(s.integrator.params.get_int("iterations", 64).unwrap(), 8);
    assert_eq!(s.accelerator.ty, "bvh");
    let loc = s.film.loc.as_ref().unwrap();
    assert_eq!(loc.to_string(), "scene/main.pbrt:6:1");
    // The film's unread parameter is reported, located.
    let unused: Vec<_> = s.film.params.unused().iter().map(|p| p.name.clone()).collect();
    assert_eq!(unused, ["filename"]);
    assert_eq!(s.film.params.unused()[0].loc.to_string(), "scene/main.pbrt:7:5");

    assert_eq!(s.textures.len(), 2);
    assert_eq!(s.textures[0].kind, TextureKind::Spectrum);
    assert_eq!(s.textures[0].class, "checkerboard");
    assert_eq!(s.texture("rough", TextureKind::Float).unwrap().class, "constant");
    assert!(s.texture("rough", TextureKind::Spectrum).is_none());

    // Default, red, dielectric, conductor (imported).
    let types: Vec<_> = s.materials.iter().map(|m| m.ty.as_str()).collect();
    assert_eq!(types, ["diffuse", "diffuse", "dielectric", "conductor"]);
    let red = s.named_material("red").unwrap();
    assert_eq!(
        red.params.get_spectrum_or_texture("reflectance").unwrap(),
        Some(SpectrumOrTexture::Texture("checks".into()))
    );
    // "type" was read to make `ty`.
    assert!(red.params.unused().is_empty());

    assert_eq!(s.lights.len(), 1);
    assert_eq!(s.lights[0].params.get_rgb("I").unwrap(), Some(Vec3::new(1.0, 2.0, 3.0)));
    assert_eq!(s.media.len(), 1);
    assert_eq!(s.media[0].ty, "homogeneous");
    // Media are the converter's to judge; the shapes inside one know it.
    assert!(s.unsupported.iter().all(|n| !n.message.contains("medi")));
    assert_eq!(s.shapes[0].inside_medium.as_deref(), Some("fog"));
    assert_eq!(s.shapes[0].outside_medium, None);

    let types: Vec<_> = s.shapes.iter().map(|s| s.ty.as_str()).collect();
    assert_eq!(types, ["sphere", "trianglemesh", "sphere", "disk", "bilinearmesh"]);
    let lit = &s.shapes[0];
    // CoordSysTransform "here" undid Identity, Translate, Rotate, Scale.
    assert_mat(lit.world_from_object, Mat4::IDENTITY);
    assert!(lit.reverse_orientation);
    assert_eq!(s.materials[lit.material].name.as_deref(), Some("red"));
    assert_eq!(lit.inside_medium.as_deref(), Some("fog"));
    assert_eq!(lit.outside_medium, None);
    let area = &s.area_lights[lit.area_light.unwrap()];
    assert_eq!(area.ty, "diffuse");
    let l = area.params.get_spectrum("L").unwrap().unwrap();
    assert_eq!(l, SpectrumValue::Blackbody(6500.0));
    // The Attribute "shape" radius applies to spheres without their own.
    assert_eq!(
        lit.geometry,
        Geometry::Sphere(Sphere {
            radius: 2.0,
            zmin: -2.0,
            zmax: 2.0,
            phimax_deg: 360.0
        })
    );
    assert_eq!(
        s.shapes[2].geometry,
        Geometry::Sphere(Sphere {
            radius: 3.0,
            zmin: -3.0,
            zmax: 3.0,
            phimax_deg: 360.0
        })
    );
    assert_eq!(s.shapes[2].loc.to_string(), "scene/inc/geometry.pbrt:1:1");
    // After the block: the anonymous dielectric, no area light, no reversal.
    let inst = &s.shapes[1];
    assert_eq!(s.materials[inst.material].ty, "dielectric");
    assert_eq!(inst.area_light, None);
    assert!(!inst.reverse_orientation);
    assert_eq!(inst.instance.as_ref().unwrap().object, "thing");
    assert_mat(inst.world_from_object, Mat4::from_translation(Vec3::new(0.0, 0.0, 7.0)));
    // The import's material and reversal ended with it.
    assert_eq!(s.materials[s.shapes[3].material].ty, "conductor");
    assert!(!s.shapes[3].reverse_orientation);
    assert_eq!(s.materials[s.shapes[4].material].ty, "dielectric");
    assert!(!s.shapes[4].reverse_orientation);
    assert_eq!(
        s.files,
        ["scene/main.pbrt", "scene/inc/geometry.pbrt", "scene/imported.pbrt"].map(PathBuf::from)
    );
}

#[test]
fn defaults_apply_without_directives() {
    let s = parse(WORLD);
    assert_eq!(
        [
            &s.film.ty,
            &s.sampler.ty,
            &s.filter.ty,
            &s.integrator.ty,
            &s.accelerator.ty,
            &s.camera.ty
        ],
        ["rgb", "zsobol", "gaussian", "volpath", "bvh", "perspective"]
    );
    assert!(s.film.loc.is_none() && s.camera.loc.is_none());
    assert_eq!(s.materials.len(), 1);
    assert_eq!(s.materials[0].ty, "diffuse");
    assert_eq!(s.camera.camera_from_world, Mat4::IDENTITY);
}

#[test]
fn the_screen_window_spans_the_shorter_axis() {
    let cam = |text: &str| parse(&format!("Camera \"perspective\" {text}\nWorldBegin\n")).camera;
    assert_eq!(cam("").screen_window(64, 32).unwrap(), [-2.0, 2.0, -1.0, 1.0]);
    assert_eq!(cam("").screen_window(32, 64).unwrap(), [-1.0, 1.0, -2.0, 2.0]);
    assert_eq!(cam("").screen_window(10, 10).unwrap(), [-1.0, 1.0, -1.0, 1.0]);
    assert_eq!(
        cam("\"float frameaspectratio\" 0.5").screen_window(64, 32).unwrap(),
        [-1.0, 1.0, -2.0, 2.0]
    );
    assert_eq!(
        cam("\"float screenwindow\" [0 1 0 1]").screen_window(64, 32).unwrap(),
        [0.0, 1.0, 0.0, 1.0]
    );
    let e = cam("\"float screenwindow\" [0 1]").screen_window(64, 32).unwrap_err();
    assert_eq!(
        e.to_string(),
        "scene/main.pbrt:1:22: \"screenwindow\" needs four values, not 2"
    );
}

// ---- transforms -------------------------------------------------------------

fn shape_transform(prefix: &str) -> Mat4 {
    let s = parse(&format!("WorldBegin\n{prefix}\nShape \"sphere\"\n"));
    s.shapes[0].world_from_object
}

fn camera_transform(prefix: &str) -> Mat4 {
    parse(&format!("{prefix}\nCamera \"perspective\"\nWorldBegin\n"))
        .camera
        .camera_from_world
}

#[test]
fn look_at_matches_hand_computed_matrices() {
    assert_mat(camera_transform("LookAt 0 0 0  0 0 1  0 1 0"), Mat4::IDENTITY);
    assert_mat(
        camera_transform("LookAt 1 2 3  1 2 10  0 1 0"),
        Mat4::from_translation(Vec3::new(-1.0, -2.0, -3.0)),
    );
    // Looking down +x with +z up: camera x (right) = world y, camera y = z,
    // camera z (forward) = x; the rows of camera-from-world.
    let m = camera_transform("LookAt 0 0 0  1 0 0  0 0 1");
    let expected = Mat4::from_cols(
        Vec4::new(0.0, 0.0, 1.0, 0.0),
        Vec4::new(1.0, 0.0, 0.0, 0.0),
        Vec4::new(0.0, 1.0, 0.0, 0.0),
        Vec4::W,
    );
    assert_mat(m, expected);
    // An eye at (0, 0, -5) looking at the origin: the origin is 5 ahead.
    let m = camera_transform("LookAt 0 0 -5  0 0 0  0 1 0");
    assert_vec(point(m, Vec3::ZERO), Vec3::new(0.0, 0.0, 5.0));
    assert_vec(point(m, Vec3::new(1.0, 0.0, 0.0)), Vec3::new(1.0, 0.0, 5.0));
    // The up vector needs not be orthogonal to the view direction.
    let m = camera_transform("LookAt 0 0 -5  0 0 0  0 1 1");
    assert_vec(point(m, Vec3::new(0.0, 1.0, 0.0)), Vec3::new(0.0, 1.0, 5.0));
    let s = parse("LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n");
    assert_mat(s.camera.world_from_camera * s.camera.camera_from_world, Mat4::IDENTITY);
    assert_vec(point(s.camera.world_from_camera, Vec3::ZERO), Vec3::new(0.0, 0.0, -5.0));
}

#[test]
fn scale_minus_one_flips_camera_x() {
    // Exporters write `Scale -1 1 1` before LookAt to turn a right-handed
    // camera into pbrt's left-handed one: CTM = S * L.
    let m = camera_transform("Scale -1 1 1\nLookAt 0 0 -5  0 0 0  0 1 0");
    assert_vec(point(m, Vec3::new(1.0, 0.0, 0.0)), Vec3::new(-1.0, 0.0, 5.0));
    assert_vec(point(m, Vec3::new(0.0, 1.0, 0.0)), Vec3::new(0.0, 1.0, 5.0));
    assert!(m.determinant() < 0.0);
    // After LookAt the scale acts in world space first: L * S.
    let m = camera_transform("LookAt 0 0 -5  0 0 0  0 1 0\nScale -1 1 1");
    assert_vec(point(m, Vec3::new(1.0, 0.0, 1.0)), Vec3::new(-1.0, 0.0, 6.0));
    // Two flips cancel.
    assert_mat(camera_transform("Scale -1 1 1\nScale -1 1 1"), Mat4::IDENTITY);
}

#[test]
fn transforms_compose_by_post_multiplication() {
    // Translate then Scale: p -> T(S(p)).
    let m = shape_transform("Translate 1 2 3\nScale 2 2 2");
    assert_vec(point(m, Vec3::ONE), Vec3::new(3.0, 4.0, 5.0));
    // Rotate 90 about z takes x to y; about x takes y to z.
    assert_vec(point(shape_transform("Rotate 90 0 0 1"), Vec3::X), Vec3::Y);
    assert_vec(point(shape_transform("Rotate 90 1 0 0"), Vec3::Y), Vec3::Z);
    assert_vec(point(shape_transform("Rotate 90 0 0 5"), Vec3::X), Vec3::Y);
    assert_vec(point(shape_transform("Rotate -90 0 1 0"), Vec3::X), Vec3::Z);
    // The 16 numbers of Transform are the matrix's columns.
    let m = shape_transform("Transform [2 0 0 0  0 3 0 0  0 0 4 0  5 6 7 1]");
    assert_mat(
        m,
        Mat4::from_cols_array(&[2., 0., 0., 0., 0., 3., 0., 0., 0., 0., 4., 0., 5., 6., 7., 1.]),
    );
    assert_vec(point(m, Vec3::ONE), Vec3::new(7.0, 9.0, 11.0));
    // ConcatTransform post-multiplies; Transform and Identity replace.
    let m = shape_transform("Translate 1 0 0\nConcatTransform [0 1 0 0  -1 0 0 0  0 0 1 0  0 0 0 1]");
    assert_vec(point(m, Vec3::X), Vec3::new(1.0, 1.0, 0.0));
    assert_mat(shape_transform("Translate 1 0 0\nIdentity"), Mat4::IDENTITY);
    assert_mat(
        shape_transform("Translate 1 0 0\nTransform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 9 1]"),
        Mat4::from_translation(Vec3::new(0.0, 0.0, 9.0)),
    );
}

#[test]
fn named_coordinate_systems_and_the_camera() {
    // The camera's coordinate system places a shape relative to the camera:
    // one unit in front of an eye at (0, 0, -5) looking at the origin.
    let s = parse(
        "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
         AttributeBegin\nCoordSysTransform \"camera\"\nTranslate 0 0 1\nShape \"sphere\"\nAttributeEnd\n\
         Translate 5 5 5\nCoordSysTransform \"world\"\nShape \"disk\"\n\
         CoordSysTransform \"nowhere\"\n",
    );
    assert_vec(
        point(s.shapes[0].world_from_object, Vec3::ZERO),
        Vec3::new(0.0, 0.0, -4.0),
    );
    assert_mat(s.shapes[1].world_from_object, Mat4::IDENTITY);
    assert_eq!(s.warnings.len(), 1);
    assert!(s.warnings[0].message.contains("nowhere"), "{:?}", s.warnings);
    assert_eq!(s.warnings[0].loc.line, 12);
    // Scale -1 1 1 before the camera: the camera space is mirrored, and so
    // is a shape placed in it.
    let s = parse(
        "Scale -1 1 1\nLookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
         CoordSysTransform \"camera\"\nTranslate 1 0 1\nShape \"sphere\"\n",
    );
    assert_vec(
        point(s.shapes[0].world_from_object, Vec3::ZERO),
        Vec3::new(-1.0, 0.0, -4.0),
    );
    assert!(s.shapes[0].flips_normals());
}

#[test]
fn reverse_orientation_and_handedness_decide_normal_flips() {
    let s = parse(
        "WorldBegin\nShape \"sphere\"\nAttributeBegin\nReverseOrientation\nShape \"sphere\"\n\
         Scale 1 -1 1\nShape \"sphere\"\nAttributeEnd\nScale 1 1 -1\nShape \"sphere\"\n",
    );
    let flips: Vec<_> = s.shapes.iter().map(|s| s.flips_normals()).collect();
    assert_eq!(flips, [false, true, false, true]);
    let rev: Vec<_> = s.shapes.iter().map(|s| s.reverse_orientation).collect();
    assert_eq!(rev, [false, true, true, false]);
}

#[test]
fn attribute_blocks_save_and_restore_the_graphics_state() {
    let s = parse(
        "WorldBegin\nMakeNamedMaterial \"m\" \"string type\" \"coateddiffuse\"\n\
         Translate 1 0 0\nAttribute \"shape\" \"float radius\" 4\n\
         AttributeBegin\n  Translate 0 1 0\n  NamedMaterial \"m\"\n  AreaLightSource \"diffuse\"\n\
           Attribute \"shape\" \"float radius\" 5\n  AttributeBegin\n    Translate 0 0 1\n    Material \"conductor\"\n    Shape \"sphere\"\n  AttributeEnd\n\
           Shape \"sphere\" \"float radius\" 6\nAttributeEnd\nShape \"sphere\"\n",
    );
    let at = |i: usize| point(s.shapes[i].world_from_object, Vec3::ZERO);
    assert_vec(at(0), Vec3::new(1.0, 1.0, 1.0));
    assert_vec(at(1), Vec3::new(1.0, 1.0, 0.0));
    assert_vec(at(2), Vec3::new(1.0, 0.0, 0.0));
    let mats: Vec<_> = s.shapes.iter().map(|x| s.materials[x.material].ty.as_str()).collect();
    assert_eq!(mats, ["conductor", "coateddiffuse", "diffuse"]);
    assert_eq!(s.shapes[0].area_light, Some(0));
    assert_eq!(s.shapes[1].area_light, Some(0));
    assert_eq!(s.shapes[2].area_light, None);
    let radii: Vec<_> = s
        .shapes
        .iter()
        .map(|x| match x.geometry {
            Geometry::Sphere(sp) => sp.radius,
            _ => 0.0,
        })
        .collect();
    // The later Attribute wins over the earlier; the shape's own wins over both.
    assert_eq!(radii, [5.0, 6.0, 4.0]);
    // Attributes are never reported unused.
    assert!(s.shapes[2].params.unused().is_empty());
}

#[test]
fn motion_is_noted_and_transform_blocks_work_as_attribute_blocks() {
    let s = parse(
        "WorldBegin\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\nShape \"sphere\"\n\
         TransformBegin\nActiveTransform StartTime\nTranslate 0 1 0\nTransformEnd\nShape \"disk\"\n",
    );
    // Both shapes move from the start transformation to the end one (the
    // transform block restores both); the converter decides what moves.
    let end = Mat4::from_translation(Vec3::new(1.0, 0.0, 0.0));
    for shape in &s.shapes {
        assert_mat(shape.world_from_object, Mat4::IDENTITY);
        let [a, b] = shape.motion.unwrap();
        assert_mat(a, Mat4::IDENTITY);
        assert_mat(b, end);
    }
    assert!(s.unsupported.is_empty());
    // A moving area light is noted, at its start transformation.
    let s = parse(
        "WorldBegin\nAttributeBegin\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n\
         AreaLightSource \"diffuse\"\nShape \"sphere\"\nAttributeEnd\nShape \"sphere\"\n",
    );
    assert_mat(s.shapes[0].world_from_object, Mat4::IDENTITY);
    assert!(s.shapes[0].motion.is_none() && s.shapes[1].motion.is_none());
    let lines: Vec<_> = s.unsupported.iter().map(|n| n.loc.line).collect();
    assert_eq!(lines, [7]);
    assert!(s.unsupported[0].message.contains("animated transformation"));
    assert_eq!(parse("TransformTimes 0.5 2\nWorldBegin\n").transform_times, [0.5, 2.0]);
    // A moving instance: its shapes start where its start transformation
    // puts them, and move as its own transformation is interpolated (the
    // shape's within the definition stays out of the interpolation).
    let s = parse(
        "WorldBegin\nObjectBegin \"o\"\nScale 2 1 1\nShape \"sphere\"\nObjectEnd\n\
         Translate 0 1 0\nActiveTransform EndTime\nRotate 90 0 0 1\nActiveTransform All\nObjectInstance \"o\"\n",
    );
    let t = Mat4::from_translation(Vec3::new(0.0, 1.0, 0.0));
    let r = Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2);
    assert_mat(
        s.shapes[0].world_from_object,
        t * Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0)),
    );
    let [a, b] = s.shapes[0].motion.unwrap();
    assert_mat(a, t);
    assert_mat(b, t * r);
    error(
        "TransformTimes 1 1\n",
        "scene/main.pbrt:1:1: TransformTimes 1 1: the times must be finite and increasing",
    );
    error(
        "ActiveTransform Sometimes\n",
        "scene/main.pbrt:1:17: ActiveTransform: expected All, StartTime or EndTime",
    );
    error(
        "WorldBegin\nTransformTimes 0 1\n",
        "scene/main.pbrt:2:1: TransformTimes is not allowed after WorldBegin",
    );
}

// ---- instances --------------------------------------------------------------

#[test]
fn object_instances_are_flattened_with_composed_transforms() {
    let s = parse(
        "WorldBegin\nMaterial \"conductor\"\n\
         ObjectInstance \"early\"\n\
         AttributeBegin\nTranslate 0 0 10\nObjectBegin \"early\"\n  Translate 1 0 0\n  Shape \"disk\"\n  AreaLightSource \"diffuse\"\n  Shape \"sphere\"\nObjectEnd\nAttributeEnd\n\
         Scale 2 2 2\nObjectInstance \"early\"\n\
         ObjectBegin \"unused\"\nShape \"sphere\"\nObjectEnd\n",
    );
    assert_eq!(s.shapes.len(), 4);
    // The definition's transform (including what preceded ObjectBegin),
    // then the instance's.
    let at = |i: usize| point(s.shapes[i].world_from_object, Vec3::ZERO);
    assert_vec(at(0), Vec3::new(1.0, 0.0, 10.0));
    assert_vec(at(2), Vec3::new(2.0, 0.0, 20.0));
    assert_eq!(s.shapes[2].instance.as_ref().unwrap().loc.line, 14);
    assert!(s.shapes.iter().all(|x| s.materials[x.material].ty == "conductor"));
    // pbrt-v4 ignores area lights in instances, and says so.
    assert!(s.shapes.iter().all(|x| x.area_light.is_none()));
    assert!(s.warnings.iter().any(|w| w.message.contains("object instances")));
    // The copies share one mesh/parameter set.
    assert!(Arc::ptr_eq(&s.shapes[0].params, &s.shapes[2].params));

    error(
        "WorldBegin\nObjectInstance \"nothing\"\n",
        "scene/main.pbrt:2:1: ObjectInstance: object \"nothing\" is not defined",
    );
    error(
        "WorldBegin\nObjectBegin \"a\"\nObjectBegin \"b\"\n",
        "scene/main.pbrt:3:1: ObjectBegin inside",
    );
    error(
        "WorldBegin\nObjectBegin \"a\"\nObjectEnd\nObjectBegin \"a\"\n",
        "scene/main.pbrt:4:1: ObjectBegin: \"a\" is defined twice",
    );
    error(
        "WorldBegin\nObjectBegin \"a\"\n",
        "scene/main.pbrt:2:1: ObjectBegin without ObjectEnd",
    );
    error(
        "WorldBegin\nObjectBegin \"a\"\nAttributeEnd\n",
        "scene/main.pbrt:3:1: AttributeEnd closes the ObjectBegin",
    );
    error(
        "WorldBegin\nAttributeBegin\nObjectBegin \"a\"\nAttributeEnd",
        "scene/main.pbrt:4:1: AttributeEnd closes",
    );
    error(
        "WorldBegin\nObjectEnd\n",
        "scene/main.pbrt:2:1: ObjectEnd without ObjectBegin",
    );
    error(
        "WorldBegin\nObjectBegin \"a\"\nNamedMaterial \"x\"\nShape \"sphere\"\nObjectEnd\n",
        "scene/main.pbrt:4:1: the shape's material \"x\" is not defined",
    );
}

// ---- Include and Import -----------------------------------------------------

#[test]
fn includes_resolve_in_the_scene_folder_then_beside_the_including_file() {
    // pbrt-v4 resolves a relative name against the top-level file's folder,
    // whichever file names it: "a/b.pbrt" inside a/one.pbrt is scene/a/b.pbrt,
    // not scene/a/a/b.pbrt, when both exist.
    let files = Files::default()
        .with(
            "scene/a/one.pbrt",
            "Include \"two.pbrt\"\nInclude \"top.pbrt\"\nInclude \"a/b.pbrt\"\n",
        )
        .with("scene/a/two.pbrt", "Shape \"sphere\" \"float radius\" 2\n")
        .with("scene/top.pbrt", "Shape \"sphere\" \"float radius\" 3\n")
        .with("scene/a/b.pbrt", "Shape \"sphere\" \"float radius\" 4\n")
        .with("scene/a/a/b.pbrt", "Shape \"sphere\" \"float radius\" 5\n");
    let s = parse_with("WorldBegin\nInclude \"a/one.pbrt\"\nShape \"disk\"\n", files).unwrap();
    let files: Vec<_> = s.shapes.iter().map(|x| x.loc.file.display().to_string()).collect();
    assert_eq!(
        files,
        [
            "scene/a/two.pbrt",
            "scene/top.pbrt",
            "scene/a/b.pbrt",
            "scene/main.pbrt"
        ]
    );
    // A name found nowhere is reported where pbrt-v4 looks for it.
    let files = Files::default().with("scene/a/one.pbrt", "Include \"a/none.pbrt\"\n");
    let e = parse_with("WorldBegin\nInclude \"a/one.pbrt\"\n", files)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("scene/a/one.pbrt:1:1: Include \"a/none.pbrt\": cannot read scene/a/none.pbrt"),
        "{e}"
    );
    // An Include may open a block that the including file closes.
    let files = Files::default().with("scene/open.pbrt", "AttributeBegin\nTranslate 1 0 0\n");
    let s = parse_with(
        "WorldBegin\nInclude \"open.pbrt\"\nShape \"disk\"\nAttributeEnd\nShape \"disk\"\n",
        files,
    )
    .unwrap();
    assert_vec(point(s.shapes[0].world_from_object, Vec3::ZERO), Vec3::X);
    assert_vec(point(s.shapes[1].world_from_object, Vec3::ZERO), Vec3::ZERO);
    // Gzipped scene files are read too.
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    std::io::Write::write_all(&mut gz, b"Shape \"sphere\"\n").unwrap();
    let files = Files::default().with("scene/g.pbrt.gz", gz.finish().unwrap());
    assert_eq!(
        parse_with("WorldBegin\nInclude \"g.pbrt.gz\"\n", files)
            .unwrap()
            .shapes
            .len(),
        1
    );
}

#[test]
fn include_errors_name_the_include() {
    let e = error(
        "WorldBegin\n  Include \"missing.pbrt\"\n",
        "scene/main.pbrt:2:3: Include \"missing.pbrt\": cannot read scene/missing.pbrt",
    );
    assert!(e.contains("no such file"), "{e}");
    error(
        "WorldBegin\nInclude \"main.pbrt\"\n",
        "scene/main.pbrt:2:1: Include \"main.pbrt\": include cycle: scene/main.pbrt -> scene/main.pbrt",
    );
    let files = Files::default()
        .with("scene/a.pbrt", "\n\nInclude \"b.pbrt\"\n")
        .with("scene/b.pbrt", "Import \"a.pbrt\"\n");
    error_with(
        "WorldBegin\nInclude \"a.pbrt\"\n",
        files,
        "scene/b.pbrt:1:1: Import \"a.pbrt\": include cycle: scene/main.pbrt -> scene/a.pbrt -> scene/b.pbrt -> scene/a.pbrt",
    );
    // A file included twice in a row (not nested) is fine.
    let files = Files::default().with("scene/s.pbrt", "Shape \"sphere\"\n");
    let s = parse_with("WorldBegin\nInclude \"s.pbrt\"\nInclude \"s.pbrt\"\n", files).unwrap();
    assert_eq!(s.shapes.len(), 2);
    // Import only in the world block, and it must close its blocks.
    error(
        "Import \"x.pbrt\"\n",
        "scene/main.pbrt:1:1: Import is only allowed after WorldBegin",
    );
    let files = Files::default().with("scene/x.pbrt", "\nAttributeBegin\n");
    error_with(
        "WorldBegin\nImport \"x.pbrt\"\n",
        files,
        "scene/x.pbrt:2:1: AttributeBegin without its end in an imported file",
    );
}

// ---- errors -----------------------------------------------------------------

#[test]
fn errors_name_file_line_and_column() {
    let cases: &[(&str, &str)] = &[
        ("Translate 1 2 x\n", "scene/main.pbrt:1:15: Translate: expected a number, got 'x'"),
        ("WorldBegin\nShape \"sphere\" \"float radius\" [ 1.2.3 ]\n", "scene/main.pbrt:2:33: \"float radius\": expected a number, got '1.2.3'"),
        ("WorldBegin\nShape \"sphere\" \"float radius\" 1e999\n", "scene/main.pbrt:2:31: \"float radius\": expected a number, got '1e999'"),
        ("WorldBegin\nShape \"sphere\" \"float radius\" 1e39\n", "scene/main.pbrt:2:31: '1e39': the number is too large"),
        ("WorldBegin\nShape \"sphere\n", "scene/main.pbrt:2:7: unterminated string"),
        ("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0\n", "scene/main.pbrt:2:33: \"point3 P\": unterminated '['"),
        ("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0\nShape \"sphere\"\n", "scene/main.pbrt:3:1: \"point3 P\": 'Shape' in a value list (missing ']' for the '[' at 2:33?)"),
        ("WorldBegin\nSphere 1\n", "scene/main.pbrt:2:1: unknown directive 'Sphere'"),
        ("WorldBegin\n\"sphere\"\n", "scene/main.pbrt:2:1: expected a directive, got \"sphere\""),
        ("WorldBegin\nWorldEnd\n", "scene/main.pbrt:2:1: unknown directive WorldEnd"),
        ("WorldBegin\nShape \"sphere\" \"float radius\" \"big\"\n", "scene/main.pbrt:2:31: \"float radius\": expected a number, got \"big\""),
        ("WorldBegin\nShape \"trianglemesh\" \"integer indices\" [0 1 2.5]\n", "scene/main.pbrt:2:45: \"integer indices\": expected an integer, got '2.5'"),
        ("WorldBegin\nShape \"trianglemesh\" \"integer indices\" [0 1 9999999999]\n", "scene/main.pbrt:2:45: \"integer indices\": expected an integer that fits in 32 bits"),
        ("WorldBegin\nShape \"sphere\" \"bool flip\" 1\n", "scene/main.pbrt:2:28: \"bool flip\": expected true or false, got '1'"),
        ("WorldBegin\nShape \"sphere\" \"string name\" [ x ]\n", "scene/main.pbrt:2:32: \"string name\": expected a quoted string, got 'x'"),
        ("WorldBegin\nShape \"sphere\" \"float3 radius\" 1\n", "scene/main.pbrt:2:16: \"float3 radius\": unknown parameter type 'float3'"),
        ("WorldBegin\nShape \"sphere\" \"radius\" 1\n", "scene/main.pbrt:2:16: \"radius\": a parameter is declared as \"type name\""),
        ("WorldBegin\nShape \"sphere\" \"float radius\" [ ]\n", "scene/main.pbrt:2:16: \"float radius\": no values"),
        ("WorldBegin\nShape \"sphere\" \"float radius\"", "scene/main.pbrt:2:16: the file ends where the value of \"float radius\" was expected"),
        ("WorldBegin\nShape \"sphere\" \"rgb c\" [1 2]\n", "scene/main.pbrt:2:16: \"rgb c\": 2 values, not a multiple of 3"),
        ("WorldBegin\nShape \"sphere\" \"rgb c\" [1 -2 3]\n", "scene/main.pbrt:2:16: \"rgb c\": a negative component"),
        ("WorldBegin\nMaterial \"conductor\" \"spectrum eta\" \"Cu.spd\"\n", "scene/main.pbrt:2:37: \"spectrum eta\" \"Cu.spd\": cannot read scene/Cu.spd"),
        ("WorldBegin\nMaterial \"conductor\" \"spectrum eta\" [\"Cu.spd\" \"metal-Cu-k\"]\n", "scene/main.pbrt:2:38: \"spectrum eta\": \"Cu.spd\" is not a spectrum pbrt-v4 names"),
        ("WorldBegin\nMaterial \"conductor\" \"spectrum eta\" [400 1 300 2]\n", "scene/main.pbrt:2:22: \"spectrum eta\": wavelengths must increase (400 then 300)"),
        ("WorldBegin\nMaterial \"conductor\" \"spectrum eta\" [400 1 500]\n", "scene/main.pbrt:2:22: \"spectrum eta\": an odd number of values"),
        ("WorldBegin\nAttributeEnd\n", "scene/main.pbrt:2:1: AttributeEnd without a matching AttributeBegin"),
        ("WorldBegin\nAttributeBegin\nAttributeBegin\nAttributeEnd\n", "scene/main.pbrt:2:1: AttributeBegin without AttributeEnd"),
        ("Shape \"sphere\"\nWorldBegin\n", "scene/main.pbrt:1:1: Shape is only allowed after WorldBegin"),
        ("AttributeBegin\n", "scene/main.pbrt:1:1: AttributeBegin is only allowed after WorldBegin"),
        ("WorldBegin\nCamera \"perspective\"\n", "scene/main.pbrt:2:1: Camera is not allowed after WorldBegin"),
        ("WorldBegin\nWorldBegin\n", "scene/main.pbrt:2:1: WorldBegin is not allowed after WorldBegin"),
        ("Camera \"perspective\"\n", "scene/main.pbrt:1:8: the scene ends before WorldBegin"),
        ("Scale 0 0 0\nCamera \"perspective\"\nWorldBegin\n", "scene/main.pbrt:2:1: Camera: the current transformation is not invertible"),
        ("LookAt 0 0 0 0 0 1 0 0 1\n", "scene/main.pbrt:1:1: LookAt: the eye is at the target, or the up vector"),
        ("Rotate 30 0 0 0\n", "scene/main.pbrt:1:1: Rotate: the axis is zero"),
        ("Transform [1 0 0 0]\n", "scene/main.pbrt:1:19: Transform: expected a number, got ']'"),
        ("Transform 1 0 0 0\n", "scene/main.pbrt:1:11: Transform: expected '[' and 16 numbers"),
        ("WorldBegin\nAttribute \"camera\" \"float x\" 1\n", "scene/main.pbrt:2:1: Attribute: unknown target \"camera\""),
        ("Option \"fastmode\" true\n", "scene/main.pbrt:1:1: Option: unknown option \"fastmode\""),
        ("WorldBegin\nTexture \"t\" \"rgb\" \"constant\"\n", "scene/main.pbrt:2:13: Texture \"t\": type \"rgb\" is neither"),
        ("WorldBegin\nTexture \"t\" \"float\" \"constant\"\nTexture \"t\" \"float\" \"scale\"\n", "scene/main.pbrt:3:1: Texture \"t\" is defined twice"),
        ("WorldBegin\nMakeNamedMaterial \"m\" \"float roughness\" 0\n", "scene/main.pbrt:2:1: MakeNamedMaterial \"m\": no \"string type\" parameter"),
        ("WorldBegin\nMakeNamedMaterial \"m\" \"string type\" \"diffuse\"\nMakeNamedMaterial \"m\" \"string type\" \"diffuse\"\n", "scene/main.pbrt:3:1: MakeNamedMaterial: \"m\" is defined twice"),
        ("WorldBegin\nNamedMaterial \"none\"\nShape \"sphere\"\n", "scene/main.pbrt:3:1: the shape's material \"none\" is not defined"),
        ("WorldBegin\nShape \"sphere\" \"float radius\" [1 2]\n", "scene/main.pbrt:2:16: \"float radius\": expected one value, got 2"),
        ("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]\n", "scene/main.pbrt:2:1: trianglemesh: vertex index 3 is out of range (\"P\" has 3 points)"),
        ("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 -1]\n", "scene/main.pbrt:2:1: trianglemesh: vertex index -1 is out of range"),
        ("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0]\n", "scene/main.pbrt:2:1: trianglemesh: vertex indices \"indices\" are required"),
        ("WorldBegin\nShape \"trianglemesh\" \"integer indices\" [0 1 2]\n", "scene/main.pbrt:2:1: trianglemesh: vertex positions \"P\" are required"),
        ("WorldBegin\nShape \"plymesh\" \"string filename\" \"gone.ply\"\n", "scene/main.pbrt:2:1: plymesh \"gone.ply\": cannot read scene/gone.ply"),
        ("WorldBegin\nShape \"plymesh\"\n", "scene/main.pbrt:2:1: plymesh: no file name given"),
        ("WorldBegin\nShape \"sphere\" \"float radius\" 0\n", "scene/main.pbrt:2:1: sphere: radius 0 must be positive and finite"),
        ("WorldBegin\nShape \"sphere\" \"float radius\" -1\n", "scene/main.pbrt:2:1: sphere: radius -1 must be positive and finite"),
        ("WorldBegin\nLightSource \"point\" \"blackbody I\" -6500\n", "scene/main.pbrt:2:21: \"blackbody I\": a blackbody's temperature -6500 (kelvin) must be positive"),
    ];
    for (text, place) in cases {
        error(text, place);
    }
    // An unreadable top-level file names just the file.
    let e = load_from(Path::new("nowhere.pbrt"), &Files::default()).unwrap_err();
    assert!(e.loc().is_none());
    assert!(e.to_string().starts_with("nowhere.pbrt: "), "{e}");
    // The library error keeps file:line:col.
    let e = parse_with("WorldBegin\n  Sphere\n", Files::default()).unwrap_err();
    assert_eq!(
        crate::error::Error::from(e).to_string(),
        "scene/main.pbrt:2: column 3: unknown directive 'Sphere'"
    );
}

// ---- parameters ---------------------------------------------------------------

#[test]
fn parameters_have_typed_lookups_and_remember_what_was_read() {
    let s = parse(
        "WorldBegin\nMaterial \"x\" \"float a\" 1.5 \"integer n\" [1 2 3] \"bool b\" false \"bool old\" \"true\"\n\
         \"string s\" \"hi\" \"point2 p2\" [1 2 3 4] \"point3 p3\" [1 2 3] \"point q\" [4 5 6] \"vector v\" [0 0 1]\n\
         \"normal3 n3\" [0 1 0] \"color c\" [0.1 0.2 0.3] \"spectrum eta\" \"metal-Cu-eta\"\n\
         \"spectrum k\" [300 1  800 3] \"blackbody L\" [3000] \"texture tex\" \"t\" \"float a\" 2.5 \"float twice\" [1 2]\n",
    );
    let p = &s.materials[1].params;
    // The later of two same-named parameters wins; the earlier is hidden.
    assert_eq!(p.get_float("a", 0.0).unwrap(), 2.5);
    assert_eq!(p.get_float("missing", 7.0).unwrap(), 7.0);
    assert_eq!(p.get_ints("n"), &[1, 2, 3]);
    assert!(p.get_int("n", 0).is_err());
    assert!(!p.get_bool("b", true).unwrap());
    assert!(p.get_bool("old", false).unwrap());
    assert_eq!(p.get_string("s").unwrap().as_deref(), Some("hi"));
    assert_eq!(p.get_point2s("p2"), [Vec2::new(1.0, 2.0), Vec2::new(3.0, 4.0)]);
    assert_eq!(p.get_point3("p3", Vec3::ZERO).unwrap(), Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(p.get_point3s("q"), [Vec3::new(4.0, 5.0, 6.0)]);
    assert_eq!(p.get_vector3("v", Vec3::ZERO).unwrap(), Vec3::Z);
    assert_eq!(p.get_normal("n3", Vec3::ZERO).unwrap(), Vec3::Y);
    assert_eq!(p.get_rgb("c").unwrap(), Some(Vec3::new(0.1, 0.2, 0.3)));
    assert_eq!(
        p.get_spectrum("eta").unwrap(),
        Some(SpectrumValue::Named("metal-Cu-eta".into()))
    );
    let Some(SpectrumValue::Sampled(k)) = p.get_spectrum("k").unwrap() else {
        panic!()
    };
    assert_eq!(k.eval(550.0), 2.0);
    assert_eq!(k.eval(200.0), 0.0);
    assert_eq!(p.get_spectrum("L").unwrap(), Some(SpectrumValue::Blackbody(3000.0)));
    assert_eq!(p.get_texture("tex").unwrap().as_deref(), Some("t"));
    assert_eq!(
        p.get_float_or_texture("tex").unwrap(),
        Some(FloatOrTexture::Texture("t".into()))
    );
    assert_eq!(p.get_float_or_texture("a").unwrap(), Some(FloatOrTexture::Value(2.5)));
    // A look-up of the wrong type finds nothing and reads nothing.
    assert_eq!(p.get_float("s", 0.5).unwrap(), 0.5);
    let e = p.get_float("twice", 0.0).unwrap_err().to_string();
    assert_eq!(e, "scene/main.pbrt:5:82: \"float twice\": expected one value, got 2");
    let unused: Vec<_> = p.unused().iter().map(|q| q.name.as_str()).collect();
    assert_eq!(unused, ["twice"]);
    assert_eq!(p.get("p3").unwrap().ty, ParamType::Point3);
    assert_eq!(p.loc_of("p3").unwrap().to_string(), "scene/main.pbrt:3:39");
}

// ---- spectra ----------------------------------------------------------------

fn chromaticity(xyz: Vec3) -> (f32, f32) {
    let sum = xyz.x + xyz.y + xyz.z;
    (xyz.x / sum, xyz.y / sum)
}

#[test]
fn blackbody_colours_are_on_the_planckian_locus() {
    // CIE 1931 chromaticities of the Planckian radiator: 6504 K (D65's CCT)
    // and 2856 K (illuminant A).
    let (x, y) = chromaticity(spectrum::blackbody_xyz(6504.0));
    assert!((x - 0.3135).abs() < 5e-4 && (y - 0.3236).abs() < 5e-4, "{x} {y}");
    let (x, y) = chromaticity(spectrum::blackbody_xyz(2856.0));
    assert!((x - 0.4476).abs() < 5e-4 && (y - 0.4074).abs() < 5e-4, "{x} {y}");
    // A cool one too, whose light is mostly in the matching functions' red
    // tail (Planck at 1500 K: x = 0.5857, y = 0.3931).
    let (x, y) = chromaticity(spectrum::blackbody_xyz(1500.0));
    assert!((x - 0.5857).abs() < 1e-3 && (y - 0.3931).abs() < 1e-3, "{x} {y}");
    // Near-white at 6504 K, a little short of green (the Planckian locus
    // passes below D65, sRGB's white: 0.3236 against 0.3290 in y); red
    // above blue at 3000 K.
    let c = spectrum::blackbody_rgb(6504.0);
    assert!((c.x / c.z - 1.0).abs() < 0.02 && (c.y / c.z - 0.95).abs() < 0.01, "{c}");
    let c = spectrum::blackbody_rgb(3000.0);
    assert!(c.x > c.y && c.y > c.z, "{c}");
    // pbrt's lights see unit luminance.
    let l = SpectrumValue::Blackbody(3000.0).light_rgb().unwrap();
    assert!((spectrum::luminance(l) - 1.0).abs() < 0.01, "{l}");
    assert_eq!(SpectrumValue::Rgb(Vec3::ONE).light_rgb(), Some(Vec3::ONE));
    assert_eq!(SpectrumValue::Named("stdillum-D65".into()).to_rgb(), None);
    // A constant spectrum of 1 has Y = 1 (equal-energy white).
    let flat = SampledSpectrum {
        lambda: vec![300.0, 900.0],
        value: vec![1.0, 1.0],
    };
    assert!((spectrum::spectrum_to_xyz(|l| flat.eval(l)).y - 1.0).abs() < 1e-4);
    // The peak-normalised spectrum has a maximum of 1.
    let peak = (360..=830)
        .map(|l| spectrum::blackbody_normalized(l as f64, 6000.0))
        .fold(0.0, f64::max);
    assert!((peak - 1.0).abs() < 1e-3, "{peak}");
    assert_eq!(spectrum::blackbody_normalized(500.0, 0.0), 0.0);
}

// ---- shapes -----------------------------------------------------------------

fn mesh(s: &Shape) -> &TriMesh {
    match &s.geometry {
        Geometry::Mesh(m) => m,
        g => panic!("not a mesh: {g:?}"),
    }
}

#[test]
fn meshes_spheres_and_disks_are_decoded() {
    let s = parse(
        "WorldBegin\n\
         Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"normal N\" [0 0 1 0 0 1 0 0 1] \"point2 uv\" [0 0 1 0]\n\
         Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0] \"integer indices\" [0 1 2 2 1 3 0]\n\
         Shape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0] \"point2 uv\" [0 0 1 0 0 1 1 1]\n\
         Shape \"sphere\" \"float radius\" 2 \"float zmax\" 1\n\
         Shape \"disk\" \"float radius\" 3 \"float height\" 1\n\
         Shape \"disk\" \"float innerradius\" 0.5\n\
         Shape \"cylinder\" \"float phimax\" 90\n\
         Shape \"teapot\"\n",
    );
    let m = mesh(&s.shapes[0]);
    assert_eq!(m.triangles, [[0, 1, 2]]);
    assert_eq!(m.normals.as_ref().unwrap().len(), 3);
    assert_eq!(m.uvs, None); // two uvs for three points: dropped, with a warning
    assert_eq!(mesh(&s.shapes[1]).triangles, [[0, 1, 2], [2, 1, 3]]);
    // The bilinear patch (p00 p10 p01 p11): both triangles face +z, as the patch.
    let b = mesh(&s.shapes[2]);
    assert_eq!(b.triangles, [[0, 1, 3], [0, 3, 2]]);
    assert_eq!(b.quads_split, 1);
    for t in &b.triangles {
        let p = t.map(|i| b.positions[i as usize]);
        assert!((p[1] - p[0]).cross(p[2] - p[0]).z > 0.0);
    }
    assert_eq!(b.uvs.as_ref().unwrap()[3], Vec2::ONE);
    assert_eq!(
        s.shapes[3].geometry,
        Geometry::Sphere(Sphere {
            radius: 2.0,
            zmin: -2.0,
            zmax: 1.0,
            phimax_deg: 360.0
        })
    );
    assert_eq!(
        s.shapes[4].geometry,
        Geometry::Disk(Disk {
            height: 1.0,
            radius: 3.0,
            inner_radius: 0.0,
            phimax_deg: 360.0
        })
    );
    // A quarter cylinder: 64 quads (a 256th of a turn each), its own
    // normals and (u, v) = (phi / phimax, (z - zmin) / (zmax - zmin)).
    let c = mesh(&s.shapes[6]);
    assert_eq!((c.triangles.len(), c.positions.len()), (128, 130));
    let (p, n, uv) = (
        c.positions[129],
        c.normals.as_ref().unwrap()[129],
        c.uvs.as_ref().unwrap()[129],
    );
    assert!(
        (p - Vec3::new(0.0, 1.0, 1.0)).length() < 1e-6 && (n - Vec3::Y).length() < 1e-6,
        "{p} {n}"
    );
    assert_eq!(uv, Vec2::ONE);
    for t in &c.triangles {
        // Wound to face outwards, as the normals do.
        let q = t.map(|i| c.positions[i as usize]);
        let centre = (q[0] + q[1] + q[2]) / 3.0;
        assert!((q[1] - q[0]).cross(q[2] - q[0]).dot(Vec3::new(centre.x, centre.y, 0.0)) > 0.0);
    }
    assert_eq!(s.shapes[7].geometry, Geometry::Other);
    let unsupported: Vec<_> = s.unsupported.iter().map(|n| (n.loc.line, n.message.as_str())).collect();
    assert_eq!(unsupported, [(9, "\"teapot\" is not a pbrt-v4 shape type"),]);
    let warnings: Vec<_> = s.warnings.iter().map(|n| (n.loc.line, n.message.as_str())).collect();
    assert_eq!(
        warnings,
        [
            (
                2,
                "trianglemesh: 2 texture coordinates \"uv\" for 3 points; they are ignored"
            ),
            (
                3,
                "trianglemesh: 7 vertex indices is not a multiple of 3; the last 1 are ignored"
            ),
        ]
    );
    assert_eq!(s.triangle_count(), 5 + 128);
    // A full sphere given its defaults explicitly is not partial.
    let s = parse(
        "WorldBegin\nShape \"sphere\" \"float radius\" 2 \"float zmin\" -2 \"float zmax\" 3 \"float phimax\" 360\n",
    );
    assert!(s.unsupported.is_empty(), "{:?}", s.unsupported);
}

fn ply_ascii(body_faces: &str, nfaces: usize) -> String {
    format!(
        "ply\nformat ascii 1.0\ncomment test\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\nproperty float s\nproperty float t\n\
         element face {nfaces}\nproperty list uchar int vertex_indices\nproperty int face_indices\nend_header\n\
         0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n2 2 0 0 0 1 0.5 0.5\n{body_faces}"
    )
}

fn ply_binary(big_endian: bool) -> Vec<u8> {
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut b = format!(
        "ply\nformat {fmt} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
         property float u\nproperty float v\nelement face 2\nproperty list uchar uint vertex_indices\nend_header\n"
    )
    .into_bytes();
    let f = |b: &mut Vec<u8>, v: f32| b.extend(if big_endian { v.to_be_bytes() } else { v.to_le_bytes() });
    for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        for v in [x, y, 0.0, x, y] {
            f(&mut b, v);
        }
    }
    let u = |b: &mut Vec<u8>, v: u32| b.extend(if big_endian { v.to_be_bytes() } else { v.to_le_bytes() });
    b.push(4);
    for i in [0, 1, 2, 3] {
        u(&mut b, i);
    }
    b.push(3);
    for i in [0, 2, 3] {
        u(&mut b, i);
    }
    b
}

#[test]
fn a_ply_normal_that_is_not_finite_is_no_normal_with_a_warning() {
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
               property float nx\nproperty float ny\nproperty float nz\nelement face 1\n\
               property list uchar int vertex_indices\nend_header\n\
               0 0 0 0 0 1\n1 0 0 nan nan nan\n0 1 0 0 0 1\n3 0 1 2\n";
    let files = Files::default().with("scene/n.ply", ply);
    let s = parse_with("WorldBegin\nShape \"plymesh\" \"string filename\" \"n.ply\"\n", files).unwrap();
    assert_eq!(mesh(&s.shapes[0]).normals, Some(vec![Vec3::Z, Vec3::ZERO, Vec3::Z]));
    assert!(
        s.warnings.iter().any(|w| w.message.starts_with(
            "plymesh \"n.ply\": 1 of 3 vertices have a normal that is not finite: the triangles around them are shaded flat"
        )),
        "{:?}",
        s.warnings
    );
}

#[test]
fn ply_meshes_read_uv_normals_quads_and_gzip() {
    let ascii = ply_ascii("4 0 1 2 3 7\n3 0 2 4 8\n5 0 1 2 3 4 9\n", 3);
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    std::io::Write::write_all(&mut gz, &ply_binary(true)).unwrap();
    let files = Files::default()
        .with("scene/m/a.ply", &ascii)
        .with("scene/m/le.ply", ply_binary(false))
        .with("scene/m/be.ply.gz", gz.finish().unwrap());
    let s = parse_with(
        "WorldBegin\nShape \"plymesh\" \"string filename\" \"m/a.ply\"\n\
         Shape \"plymesh\" \"string filename\" \"m/le.ply\"\n\
         Shape \"plymesh\" \"string filename\" \"m/be.ply.gz\"\n\
         Shape \"plymesh\" \"string filename\" \"m/a.ply\" \"texture displacement\" \"d\"\n",
        files,
    )
    .unwrap();
    let a = mesh(&s.shapes[0]);
    // The quad (f0 f1 f2 f3) becomes (f0 f1 f2), (f0 f2 f3); the pentagon is skipped.
    assert_eq!(a.triangles, [[0, 1, 2], [0, 2, 3], [0, 2, 4]]);
    assert_eq!(a.quads_split, 1);
    assert_eq!(a.uvs.as_ref().unwrap()[4], Vec2::new(0.5, 0.5));
    assert_eq!(a.normals.as_ref().unwrap()[1], Vec3::Z);
    assert_eq!(a.file.as_deref(), Some(Path::new("scene/m/a.ply")));
    assert!(s
        .warnings
        .iter()
        .any(|w| w.message.contains("1 faces of other than 3 or 4 vertices skipped")));
    let le = mesh(&s.shapes[1]);
    let be = mesh(&s.shapes[2]);
    assert_eq!(
        le,
        &TriMesh {
            file: le.file.clone(),
            ..be.clone()
        }
    );
    assert_eq!(le.triangles, [[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
    assert_eq!(le.uvs.as_ref().unwrap()[2], Vec2::ONE);
    assert_eq!(le.normals, None);
    // The same file is read once and shared.
    assert!(Arc::ptr_eq(
        match &s.shapes[0].geometry {
            Geometry::Mesh(m) => m,
            _ => unreachable!(),
        },
        match &s.shapes[3].geometry {
            Geometry::Mesh(m) => m,
            _ => unreachable!(),
        }
    ));
    assert!(s.unsupported.iter().any(|n| n.message.contains("displacement")));
    assert_eq!(s.files.len(), 4);
}

#[test]
fn many_ply_files_decode_together_into_their_own_shapes_with_warnings_and_errors_in_file_order() {
    // Forty files, each a quad moved by its number, the odd ones with a
    // face to skip (a warning each), and one inside an object instanced twice.
    let quad = |k: usize, skip: bool| {
        let faces = if skip {
            "4 0 1 2 3 7\n5 0 1 2 3 4 9\n"
        } else {
            "4 0 1 2 3 7\n"
        };
        ply_ascii(faces, if skip { 2 } else { 1 }).replacen("0 0 0 0 0 1 0 0", &format!("{k} 0 0 0 0 1 0 0"), 1)
    };
    let mut files = Files::default();
    let mut text =
        String::from("WorldBegin\nObjectBegin \"o\"\nShape \"plymesh\" \"string filename\" \"p39.ply\"\nObjectEnd\n");
    for k in 0..40 {
        files = files.with(&format!("scene/p{k}.ply"), quad(k, k % 2 == 1));
        if k < 39 {
            text += &format!("Shape \"plymesh\" \"string filename\" \"p{k}.ply\"\n");
        }
    }
    text += "ObjectInstance \"o\"\nObjectInstance \"o\"\n";
    let s = parse_with(&text, files).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.shapes.len(), 41);
    for (i, shape) in s.shapes.iter().enumerate() {
        let k = i.min(39);
        let m = mesh(shape);
        assert_eq!(m.positions[0].x, k as f32, "shape {i}");
        assert_eq!(m.triangles.len(), 2, "shape {i}");
        assert_eq!(m.file.as_deref(), Some(Path::new(&format!("scene/p{k}.ply"))));
    }
    // The object's file was read first (its directive comes first).
    let skipped: Vec<&str> = s
        .warnings
        .iter()
        .filter(|w| w.message.contains("faces of other than 3 or 4 vertices skipped"))
        .map(|w| w.message.split('"').nth(1).unwrap_or(""))
        .collect();
    let expected: Vec<String> = std::iter::once(39)
        .chain((1..39).step_by(2))
        .map(|k| format!("p{k}.ply"))
        .collect();
    assert_eq!(skipped, expected);
    // Of two bad files, the one named first is the error, whichever decodes first.
    let mut files = Files::default();
    let mut text = String::from("WorldBegin\n");
    for k in 0..40 {
        let body = match k {
            12 => ply_ascii("3 0 1 9\n", 1),
            30 => ply_ascii("3 0 1\n", 1),
            _ => quad(k, false),
        };
        files = files.with(&format!("scene/p{k}.ply"), body);
        text += &format!("Shape \"plymesh\" \"string filename\" \"p{k}.ply\"\n");
    }
    let e = error_with(&text, files, "scene/main.pbrt:14:1: plymesh \"p12.ply\": scene/p12.ply");
    assert!(e.contains("vertex index 9 is out of range"), "{e}");
}

/// The binary PLY without its last index.
fn truncated_binary() -> Vec<u8> {
    let b = ply_binary(false);
    b[..b.len() - 4].to_vec()
}

#[test]
fn malformed_ply_files_are_errors_naming_the_shape_and_the_file() {
    // The crate's one PLY reader (scene::mesh::ply) names the file and line.
    let cases: &[(Vec<u8>, &str)] = &[
        (
            ply_ascii("3 0 1 5\n", 1).into_bytes(),
            "scene/x.ply:22: face 0 vertex index 5 is out of range (0..5)",
        ),
        (
            ply_ascii("3 0 1\n", 1).into_bytes(),
            "scene/x.ply:22: unexpected end of file reading face 0",
        ),
        (ply_ascii("3 0 1 z\n", 1).into_bytes(), "scene/x.ply:22: bad number 'z'"),
        (
            b"ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\nend_header\n1\n".to_vec(),
            "scene/x.ply:3: element 'vertex' declares 1000000000 items",
        ),
        (b"plx\n".to_vec(), "scene/x.ply:1: not a PLY file"),
        (truncated_binary(), "file truncated"),
    ];
    for (bytes, what) in cases {
        let files = Files::default().with("scene/x.ply", bytes);
        let e = error_with(
            "WorldBegin\nShape \"plymesh\" \"string filename\" \"x.ply\"\n",
            files,
            "scene/main.pbrt:2:1: plymesh \"x.ply\": scene/x.ply",
        );
        assert!(e.contains(what), "'{e}' does not say '{what}'");
    }
    // The binary file's error names the offset where the missing index starts.
    let cut = truncated_binary();
    let files = Files::default().with("scene/x.ply", &cut);
    let e = error_with(
        "WorldBegin\nShape \"plymesh\" \"string filename\" \"x.ply\"\n",
        files,
        "scene/main.pbrt:2:1",
    );
    assert!(
        e.contains(&format!("scene/x.ply: at byte offset {}: file truncated", cut.len())),
        "{e}"
    );
    let files = Files::default().with("scene/x.ply.gz", b"not gzip");
    let e = error_with(
        "WorldBegin\nShape \"plymesh\" \"string filename\" \"x.ply.gz\"\n",
        files,
        "scene/main.pbrt:2:1: plymesh \"x.ply.gz\"",
    );
    assert!(e.contains("cannot decompress"), "{e}");
}

// ---- the real scenes --------------------------------------------------------

/// `../shared/bitterli/NAME/scene-v4.pbrt` beside the repository; under CI
/// (`CI` set) it must be there, elsewhere a missing copy skips the test.
fn bitterli(name: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/bitterli")
        .join(name)
        .join("scene-v4.pbrt");
    if path.is_file() {
        return Some(path);
    }
    if std::env::var_os("CI").is_some() {
        panic!("{} is missing (CI must have ../shared/bitterli)", path.display());
    }
    eprintln!("skipped: {} is not there", path.display());
    None
}

fn mesh_of(s: &PbrtScene, i: usize) -> &TriMesh {
    mesh(&s.shapes[i])
}

#[test]
fn bitterli_cornell_box_reads_as_written() {
    let Some(path) = bitterli("cornell-box") else { return };
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.shapes.len(), 8);
    assert_eq!(s.materials.len(), 9); // 8 named and the default
    assert_eq!(s.area_lights.len(), 1);
    assert_eq!(s.lights.len(), 0);
    assert_eq!(s.triangle_count(), 36);
    assert_eq!(s.integrator.ty, "path");
    assert_eq!(s.integrator.params.get_int("maxdepth", 5).unwrap(), 65);
    assert_eq!(s.sampler.params.get_int("pixelsamples", 16).unwrap(), 512);
    assert_eq!(s.filter.ty, "gaussian");
    assert_eq!(s.filter.params.get_float("xradius", 0.0).unwrap(), 1.5);
    assert_eq!(s.film.params.get_int("xresolution", 0).unwrap(), 1024);
    assert_eq!(s.camera.params.get_float("fov", 90.0).unwrap(), 19.5);
    // Transform [1 0 0 0  0 1 0 0  0 0 -1 0  0 -1 6.8 1]: the eye at (0, 1, 6.8).
    assert_vec(point(s.camera.world_from_camera, Vec3::ZERO), Vec3::new(0.0, 1.0, 6.8));
    assert_vec(
        s.camera.world_from_camera.transform_vector3(Vec3::Z),
        Vec3::new(0.0, 0.0, -1.0),
    );
    let light = &s.shapes[7];
    let area = &s.area_lights[light.area_light.unwrap()];
    assert_eq!(area.params.get_rgb("L").unwrap(), Some(Vec3::new(17.0, 12.0, 4.0)));
    assert_eq!(s.materials[light.material].name.as_deref(), Some("Light"));
    assert_eq!(light.loc.to_string(), format!("{}:147:5", path.display()));
    let left = s.named_material("LeftWall").unwrap();
    assert_eq!(
        left.params.get_rgb("reflectance").unwrap(),
        Some(Vec3::new(0.63, 0.065, 0.05))
    );
    // The light faces down: its triangles' normal (pbrt's rule) is -y.
    let m = mesh_of(&s, 7);
    let p = m.triangles[0].map(|i| light.world_from_object.transform_point3(m.positions[i as usize]));
    let n = (p[1] - p[0]).cross(p[2] - p[0]);
    assert!(!light.flips_normals() && n.y < 0.0, "{n}");
    assert!(s.unsupported.is_empty(), "{:?}", s.unsupported);
}

#[test]
fn bitterli_veach_mis_reads_as_written() {
    let Some(path) = bitterli("veach-mis") else { return };
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.shapes.len(), 9);
    assert_eq!(s.materials.len(), 7);
    assert_eq!(s.area_lights.len(), 3);
    let spheres: Vec<_> = s
        .shapes
        .iter()
        .filter_map(|x| match x.geometry {
            Geometry::Sphere(sp) => Some((sp.radius, point(x.world_from_object, Vec3::ZERO), x.area_light)),
            _ => None,
        })
        .collect();
    assert_eq!(spheres.len(), 3);
    assert_eq!(spheres[0].0, 1.0);
    assert_eq!(spheres[2].0, 0.05);
    assert_vec(spheres[0].1, Vec3::new(0.0, 6.5, -2.8));
    assert_vec(spheres[2].1, Vec3::new(0.0, 6.5, 2.7));
    let radiance: Vec<_> = spheres
        .iter()
        .map(|sp| s.area_lights[sp.2.unwrap()].params.get_rgb("L").unwrap().unwrap().x)
        .collect();
    assert_eq!(radiance, [7.599088, 30.396353, 3039.6353]);
    let smooth = s.named_material("Smooth").unwrap();
    assert_eq!(smooth.ty, "conductor");
    assert_eq!(smooth.params.get_float("uroughness", 0.0).unwrap(), 0.01);
    assert!(!smooth.params.get_bool("remaproughness", true).unwrap());
    assert_eq!(
        smooth.params.get_spectrum("eta").unwrap(),
        Some(SpectrumValue::Rgb(Vec3::new(0.200438, 0.924033, 1.102212)))
    );
    assert_eq!(s.film.params.get_int("xresolution", 0).unwrap(), 1280);
    assert_eq!(s.integrator.params.get_int("maxdepth", 5).unwrap(), 3);
    assert_eq!(s.filter.ty, "triangle");
}

#[test]
fn bitterli_water_caustic_reads_as_written() {
    let Some(path) = bitterli("water-caustic") else { return };
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.shapes.len(), 10);
    assert_eq!(s.materials.len(), 10);
    assert_eq!(s.area_lights.len(), 1);
    assert_eq!(s.integrator.ty, "sppm");
    assert_eq!(s.integrator.params.get_float("radius", 0.0).unwrap(), 0.01);
    assert_eq!(s.integrator.params.get_int("maxdepth", 0).unwrap(), 9);
    let water = s.named_material("Water").unwrap();
    assert_eq!(water.ty, "dielectric");
    assert_eq!(water.params.get_float("eta", 1.5).unwrap(), 1.8);
    // Two PLY meshes, stretched by 1.5 in y.
    let surface = mesh_of(&s, 8);
    assert_eq!(surface.positions.len(), 63768);
    assert_eq!(surface.triangles.len(), 102938);
    assert!(surface.normals.is_some() && surface.uvs.is_some());
    assert_vec(surface.positions[0], Vec3::new(-0.329465, 1.048474, 1.0));
    let bottom = mesh_of(&s, 9);
    assert_eq!((bottom.positions.len(), bottom.triangles.len()), (519, 513));
    assert!(bottom.normals.is_none() && bottom.uvs.is_some());
    assert_mat(
        s.shapes[9].world_from_object,
        Mat4::from_scale(Vec3::new(1.0, 1.5, 1.0)),
    );
    assert_eq!(s.materials[s.shapes[9].material].name.as_deref(), Some("Water"));
    let area = &s.area_lights[s.shapes[7].area_light.unwrap()];
    assert_eq!(
        area.params.get_rgb("L").unwrap(),
        Some(Vec3::new(541126.75, 381971.8, 127323.94))
    );
    assert_eq!(s.files.len(), 3);
}

// ---- robustness ---------------------------------------------------------------

/// A small deterministic generator (SplitMix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const SAMPLE: &str = r#"LookAt 0 1 -5  0 1 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 64 ] "integer yresolution" [ 64 ]
WorldBegin
Texture "t" "spectrum" "checkerboard" "rgb tex1" [ 1 1 1 ]
MakeNamedMaterial "white" "string type" [ "diffuse" ] "texture reflectance" "t"
AttributeBegin
  AreaLightSource "diffuse" "blackbody L" [ 5000 ]
  Translate 0 2 0
  Shape "bilinearmesh" "point3 P" [ -1 0 -1 1 0 -1 -1 0 1 1 0 1 ]
AttributeEnd
ObjectBegin "o"
  NamedMaterial "white"
  Shape "trianglemesh" "point3 P" [ 0 0 0 1 0 0 0 1 0 ] "integer indices" [ 0 1 2 ]
ObjectEnd
Scale -1 1 1
ObjectInstance "o"
Include "inc.pbrt"
Shape "plymesh" "string filename" "m.ply"
"#;

#[test]
fn truncated_and_mutated_scenes_never_panic() {
    let base = match bitterli("cornell-box") {
        Some(p) => std::fs::read_to_string(p).unwrap(),
        None => SAMPLE.to_string(),
    };
    let ply = ply_ascii("4 0 1 2 3 7\n3 0 2 4 8\n", 2);
    let pieces: &[&[u8]] = &[
        b" ",
        b"\n",
        b"[",
        b"]",
        b"\"",
        b"#",
        b"\\",
        b"-",
        b"1e38",
        b"AttributeBegin",
        b"AttributeEnd",
        b"ObjectBegin \"o\"",
        b"ObjectEnd",
        b"Include \"inc.pbrt\"",
        b"Import \"main.pbrt\"",
        b"\xff",
        b"0",
        b"e",
        b"\"integer indices\" [ 0 1 99 ]",
        b"Shape \"plymesh\" \"string filename\" \"m.ply\"",
        b"WorldBegin",
    ];
    let mut rng = Rng(0x5eed);
    // Unchanged, the sample loads.
    let files = Files::default()
        .with("scene/main.pbrt", SAMPLE)
        .with("scene/inc.pbrt", "Shape \"sphere\"\n")
        .with("scene/m.ply", &ply);
    let s = load_from(Path::new("scene/main.pbrt"), &files).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.shapes.len(), 4);
    for text in [base.as_bytes(), SAMPLE.as_bytes()] {
        let run = |bytes: Vec<u8>, ply: &[u8]| {
            let files = Files::default()
                .with("scene/main.pbrt", &bytes)
                .with("scene/inc.pbrt", "Shape \"sphere\"\n")
                .with("scene/m.ply", ply);
            let _ = load_from(Path::new("scene/main.pbrt"), &files);
        };
        // Every truncation on a stride, and random ones.
        for cut in (0..text.len()).step_by(7) {
            run(text[..cut].to_vec(), ply.as_bytes());
        }
        for _ in 0..300 {
            let mut bytes = text.to_vec();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(bytes.len() + 1);
                match rng.below(3) {
                    0 if at < bytes.len() => {
                        let end = (at + 1 + rng.below(12)).min(bytes.len());
                        bytes.drain(at..end);
                    }
                    1 => {
                        let piece = pieces[rng.below(pieces.len())];
                        bytes.splice(at..at, piece.iter().copied());
                    }
                    _ if at < bytes.len() => bytes[at] = rng.next() as u8,
                    _ => {}
                }
            }
            let mut p = ply.as_bytes().to_vec();
            let at = rng.below(p.len());
            p[at] = rng.next() as u8;
            run(bytes, &p[..p.len() - rng.below(20)]);
        }
    }
}

// ---- what pbrt-v4 accepts beyond the Bitterli scenes ------------------------

fn converted(text: &str, files: Files, lenient: bool) -> std::result::Result<convert::Converted, String> {
    let scene = parse_with(text, files).map_err(|e| e.to_string())?;
    convert::convert(&scene, Path::new("scene/main.pbrt"), lenient).map_err(|e| e.to_string())
}

#[test]
fn spectrum_files_read_as_the_same_pairs_inline() {
    let files = Files::default()
        .with("scene/spds/k.spd", "# gold, k\n400 1.5  # blue\n500\t2.0\n\n600 3.25\n")
        .with("scene/spds/odd.spd", "400 1\n500\n")
        .with("scene/spds/down.spd", "400 1\n500 2\n450 3\n")
        .with("scene/spds/word.spd", "400 1\n500 two\n");
    let s = parse_with(
        "WorldBegin\nMaterial \"conductor\" \"spectrum k\" \"spds/k.spd\"\n\
         Material \"conductor\" \"spectrum k\" [400 1.5 500 2 600 3.25]\nShape \"sphere\"\n",
        files,
    )
    .unwrap();
    let values = |i: usize| match &s.materials[i].params.get("k").unwrap().values {
        Values::Floats(v) => v.clone(),
        v => panic!("{v:?}"),
    };
    let n = s.materials.len();
    assert_eq!(values(n - 2), [400.0, 1.5, 500.0, 2.0, 600.0, 3.25]);
    assert_eq!(values(n - 2), values(n - 1));
    assert!(s.files.iter().any(|f| f == Path::new("scene/spds/k.spd")));
    // A bad file is named with its own line, at the parameter's place.
    for (file, what) in [
        (
            "odd",
            "scene/spds/odd.spd:2: 3 values; a spectrum file holds wavelength / value pairs",
        ),
        (
            "down",
            "scene/spds/down.spd:3: wavelengths must increase (500 then 450)",
        ),
        ("word", "scene/spds/word.spd:2: \"two\" is not a number"),
    ] {
        let files = Files::default()
            .with("scene/spds/odd.spd", "400 1\n500\n")
            .with("scene/spds/down.spd", "400 1\n500 2\n450 3\n")
            .with("scene/spds/word.spd", "400 1\n500 two\n");
        error_with(
            &format!("WorldBegin\nMaterial \"conductor\" \"spectrum k\" \"spds/{file}.spd\"\n"),
            files,
            &format!("scene/main.pbrt:2:35: \"spectrum k\": spectrum file {what}"),
        );
    }
}

#[test]
fn interface_and_none_materials_make_no_surface() {
    let text =
        "WorldBegin\nShape \"sphere\"\nAttributeBegin\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 2\n\
                AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\nShape \"sphere\" \"float radius\" 3\nAttributeEnd\n\
                MakeNamedMaterial \"n\" \"string type\" \"none\"\nNamedMaterial \"n\"\nShape \"disk\"\n";
    let c = converted(text, Files::default(), false).unwrap();
    // Only the first sphere is left: no light, no disk.
    assert_eq!(c.desc.spheres.len(), 1, "{:?}", c.desc.spheres);
    assert_eq!(c.desc.spheres[0].sphere.radius, 1.0);
    assert!(c.desc.lights.is_empty() && c.desc.disks.is_empty());
    assert!(
        c.warnings
            .iter()
            .any(|w| w.starts_with("scene/main.pbrt:7: area light ignored") && w.contains("\"interface\"")),
        "{:?}",
        c.warnings
    );
}

#[test]
fn an_albedo_above_one_is_refused_at_its_place_as_pbrt_refuses_it() {
    use crate::material::Material;
    // pbrt-v4 exits with "used as an albedo has > 1 component"; a material
    // reached through a mix is checked too.
    for (text, line) in [
        (
            "WorldBegin\nMaterial \"diffuse\" \"rgb reflectance\" [0.2 0.5 1.5]\nShape \"sphere\"\n",
            2,
        ),
        (
            "WorldBegin\nMakeNamedMaterial \"a\" \"string type\" \"diffuse\"\n\
             MakeNamedMaterial \"b\" \"string type\" \"coateddiffuse\"\n  \"rgb reflectance\" [0 0 9]\n\
             Material \"mix\" \"string materials\" [\"a\" \"b\"]\nShape \"sphere\"\n",
            4,
        ),
        (
            "WorldBegin\nMaterial \"diffusetransmission\" \"rgb transmittance\" [1.01 0 0]\nShape \"sphere\"\n",
            2,
        ),
    ] {
        let e = converted(text, Files::default(), false).unwrap_err();
        assert!(
            e.contains(&format!("scene/main.pbrt:{line}:")) && e.contains("has a component above 1"),
            "{e}"
        );
        // --lenient renders it clamped to 1.
        let c = converted(text, Files::default(), true).unwrap();
        assert!(c.warnings.iter().any(|w| w.contains("above 1")), "{:?}", c.warnings);
    }
    let text = "WorldBegin\nMaterial \"diffuse\" \"rgb reflectance\" [0.2 0.5 1.5]\nShape \"sphere\"\n";
    let c = converted(text, Files::default(), true).unwrap();
    let m = c.desc.materials.last().unwrap().1.clone();
    assert_eq!(m, Material::diffuse(0.2, 0.5, 1.0));
    // 1 itself is an albedo pbrt-v4 takes.
    let text = "WorldBegin\nMaterial \"diffuse\" \"rgb reflectance\" [1 1 1]\nShape \"sphere\"\n";
    assert!(converted(text, Files::default(), false).is_ok());
}

#[test]
fn bump_maps_wrap_their_material_even_in_a_mix() {
    use crate::material::Material;
    let text = "WorldBegin\nTexture \"b\" \"float\" \"constant\" \"float value\" 0.1\n\
                MakeNamedMaterial \"gold\" \"string type\" \"conductor\" \"texture displacement\" \"b\"\n\
                NamedMaterial \"gold\"\nShape \"sphere\"\n";
    let c = converted(text, Files::default(), false).unwrap();
    let material =
        |c: &convert::Converted, name: &str| c.desc.materials.iter().find(|(n, _)| n == name).unwrap().1.clone();
    let Material::Bumped { base, displacement } = material(&c, "gold") else {
        panic!("{:?}", material(&c, "gold"));
    };
    assert!(matches!(*base, Material::Conductor { .. }), "{base:?}");
    assert_eq!(displacement.as_constant(), Some(Vec3::splat(0.1)));
    assert!(c.warnings.is_empty(), "{:?}", c.warnings);
    // A bump map on a material only a mix uses goes with it into the mix.
    let mixed = "WorldBegin\nMakeNamedMaterial \"gold\" \"string type\" \"conductor\" \"float displacement\" 0.2\n\
                 MakeNamedMaterial \"d\" \"string type\" \"diffuse\"\n\
                 Material \"mix\" \"string materials\" [\"d\" \"gold\"]\nShape \"sphere\"\n";
    let c = converted(mixed, Files::default(), false).unwrap();
    let m = c.desc.materials.last().unwrap().1.clone();
    let Material::Mix { materials, .. } = &m else {
        panic!("{m:?}")
    };
    assert!(
        matches!(materials[0], Material::Diffuse { .. }) && materials[1].is_bumped(),
        "{m:?}"
    );
    // A normal map that is not there is an error at its place.
    let text = "WorldBegin\nMakeNamedMaterial \"gold\" \"string type\" \"conductor\"\n\
                \"string normalmap\" \"n.png\"\nNamedMaterial \"gold\"\nShape \"sphere\"\n";
    let e = converted(text, Files::default(), false).unwrap_err();
    assert!(
        e.starts_with("scene/main.pbrt:3: column 1: normal map \"n.png\" not found"),
        "{e}"
    );
}

#[test]
fn a_normal_map_wraps_its_material_read_as_linear_rgb() {
    use crate::material::Material;
    let dir = tempfile::tempdir().unwrap();
    // One texel, (128, 64, 255): linear, as pbrt-v4 reads every normal map.
    ::image::save_buffer(
        dir.path().join("n.png"),
        &[128, 64, 255],
        1,
        1,
        ::image::ColorType::Rgb8,
    )
    .unwrap();
    let file = dir.path().join("main.pbrt");
    std::fs::write(
        &file,
        "WorldBegin\nMakeNamedMaterial \"gold\" \"string type\" \"conductor\" \"string normalmap\" \"n.png\" \
         \"float displacement\" 0.5\nNamedMaterial \"gold\"\nShape \"sphere\"\n",
    )
    .unwrap();
    let loaded = crate::scene::load(file.to_str().unwrap(), &Default::default()).unwrap();
    let m = &loaded.desc.materials.iter().find(|(n, _)| n == "gold").unwrap().1;
    // The normal map wins over the displacement, as in pbrt-v4.
    let Material::NormalMapped { base, map, .. } = m else {
        panic!("{m:?}")
    };
    assert!(matches!(**base, Material::Conductor { .. }), "{base:?}");
    assert_eq!(map.pixel(0), Vec3::new(128.0, 64.0, 255.0) / 255.0);
}

#[test]
fn images_decoded_ahead_are_the_ones_the_textures_use() {
    use crate::material::Material;
    use crate::texture::Texture;
    let dir = tempfile::tempdir().unwrap();
    for (name, texel) in [("a.png", [200u8, 100, 50]), ("b.png", [10, 20, 30])] {
        ::image::save_buffer(dir.path().join(name), &texel, 1, 1, ::image::ColorType::Rgb8).unwrap();
    }
    let file = dir.path().join("main.pbrt");
    // One file under two encodings is two images; the default encoding of
    // a PNG is sRGB.
    std::fs::write(
        &file,
        "WorldBegin\n\
         Texture \"a\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\"\n\
         Texture \"a2\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\" \"string encoding\" \"gamma 2.2\"\n\
         Texture \"b\" \"spectrum\" \"imagemap\" \"string filename\" \"b.png\" \"string encoding\" \"linear\"\n\
         Texture \"gone\" \"spectrum\" \"imagemap\" \"string filename\" \"missing.png\"\n\
         MakeNamedMaterial \"ma\" \"string type\" \"diffuse\" \"texture reflectance\" \"a\"\n\
         MakeNamedMaterial \"ma2\" \"string type\" \"diffuse\" \"texture reflectance\" \"a2\"\n\
         MakeNamedMaterial \"mb\" \"string type\" \"diffuse\" \"texture reflectance\" \"b\"\n\
         NamedMaterial \"ma\"\nShape \"sphere\"\nNamedMaterial \"ma2\"\nShape \"sphere\"\n\
         NamedMaterial \"mb\"\nShape \"sphere\"\n",
    )
    .unwrap();
    let scene = super::load(&file).unwrap();
    let ahead = convert::decode_images(&scene);
    // The missing file is left for the conversion (which does not meet it:
    // no material uses it).
    assert_eq!(ahead.len(), 3);
    let c = convert::convert(&scene, &file, false).unwrap();
    for name in ["ma", "ma2", "mb"] {
        let m = &c.desc.materials.iter().find(|(n, _)| n == name).unwrap().1;
        let Material::Diffuse {
            reflectance: Texture::Image(t),
        } = m
        else {
            panic!("{m:?}")
        };
        // The same decoded image: the conversion found it in the cache.
        assert!(ahead.iter().any(|a| Arc::ptr_eq(a, &t.image)), "{name}");
    }
}

#[test]
fn settings_and_lights_that_cannot_render_are_refused_at_their_place() {
    for (text, what) in [
        ("Sampler \"halton\" \"integer pixelsamples\" -1\nWorldBegin\n", "scene/main.pbrt:1: Sampler: pixelsamples -1: must be at least 1"),
        ("Sampler \"stratified\" \"integer xsamples\" -2\nWorldBegin\n", "scene/main.pbrt:1: Sampler: xsamples -2, ysamples 4: must be at least 1"),
        ("Integrator \"path\" \"integer maxdepth\" -5\nWorldBegin\n", "scene/main.pbrt:1: Integrator: maxdepth -5 must be >= 0"),
        ("Camera \"perspective\" \"float lensradius\" -1\nWorldBegin\n", "scene/main.pbrt:1: Camera: lensradius -1 must be >= 0"),
        ("WorldBegin\nLightSource \"point\" \"rgb I\" [3e38 3e38 3e38]\n", "scene/main.pbrt:2: point light: its power is inf, beyond the limit of 1e15"),
        ("WorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1] \"float scale\" -1\n", "scene/main.pbrt:2: point light: its power [-12.566371, -12.566371, -12.566371] must be >= 0"),
        ("Film \"rgb\" \"float iso\" 1e30\nWorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1]\n", "scene/main.pbrt:3: point light: its power is 1.2566372e29, beyond"),
        ("WorldBegin\nAreaLightSource \"diffuse\" \"float power\" 10\nShape \"sphere\" \"float radius\" 1e-25\n", "scene/main.pbrt:3: sphere light: its power is not a number"),
        ("WorldBegin\nLightSource \"spot\" \"rgb I\" [1 1 1] \"float power\" 10 \"float coneangle\" 1e-20 \"float conedelta\" 0\n", "scene/main.pbrt:2: spot light: its intensity is inf"),
    ] {
        let e = converted(text, Files::default(), false).unwrap_err();
        assert!(e.starts_with(what), "{text}: {e}");
        assert!(!e.contains('\n') && !e.contains("Vec3("), "{e}");
    }
}

#[test]
fn iso_and_shutter_time_scale_the_lights_as_pbrt_films_do() {
    let power = |pre: &str| {
        let text = format!(
            "{pre}WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 2 3]\nShape \"sphere\"\nAttributeEnd\n\
             LightSource \"point\" \"rgb I\" [1 1 1]\n"
        );
        let c = converted(&text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
        c.desc.lights.iter().map(|l| l.power()).collect::<Vec<_>>()
    };
    let base = power("");
    assert_eq!(base.len(), 2);
    for (pre, k) in [
        ("Film \"rgb\" \"float iso\" 400\n", 4.0),
        (
            "Camera \"perspective\" \"float shutteropen\" 0.25 \"float shutterclose\" 0.75\n",
            0.5,
        ),
        (
            "Camera \"perspective\" \"float shutterclose\" 0.5\nFilm \"rgb\" \"float iso\" 300\n",
            1.5,
        ),
    ] {
        for (a, b) in power(pre).iter().zip(&base) {
            assert!(
                (*a - *b * k).abs().max_element() < 1e-4 * b.max_element(),
                "{pre}: {a} vs {b} x {k}"
            );
        }
    }
    for (pre, what) in [
        (
            "Film \"rgb\" \"float iso\" 0\n",
            "scene/main.pbrt:1: Film: iso 0 must be positive",
        ),
        (
            "Camera \"perspective\" \"float shutteropen\" 1\n",
            "scene/main.pbrt:1: Camera: the shutter closes at 1, not after it opens at 1",
        ),
    ] {
        let e = converted(&format!("{pre}WorldBegin\n"), Files::default(), false).unwrap_err();
        assert!(e.starts_with(what), "{e}");
    }
}

#[test]
fn loop_subdivision_surfaces_become_limit_triangles_facing_as_pbrts() {
    // A tetrahedron wound outwards, one level: 4 x 4 triangles on the limit
    // surface, inside the control hull, every vertex with a unit normal.
    let tet = "\"point3 P\" [0 0 0 1 0 0 0 1 0 0 0 1] \"integer indices\" [0 2 1 0 1 3 0 3 2 1 2 3]";
    let text = format!("WorldBegin\nShape \"loopsubdiv\" \"integer levels\" 1 {tet}\n");
    let c = converted(&text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    let tris = &c.desc.triangles;
    assert_eq!(tris.len(), 16);
    // The default camera shows pbrt's picture as the mirror image of ours
    // (x negated); mirrored back, points are pbrt's.
    assert!(c.mirrored);
    let centre = Vec3::splat(0.25);
    for t in tris.iter() {
        let ns = t.normals.expect("limit normals").map(|n| n * Vec3::new(-1.0, 1.0, 1.0));
        let v = t.vertices.map(|p| p * Vec3::new(-1.0, 1.0, 1.0));
        // The mirror reverses the winding too.
        let winding = -(v[1] - v[0]).cross(v[2] - v[0]);
        for (p, n) in v.iter().zip(ns) {
            assert!((n.length() - 1.0).abs() < 1e-5);
            assert!(p.min_element() > -1e-6 && p.x + p.y + p.z < 1.0 + 1e-6, "{p}");
            // pbrt-v4's limit normals point inwards on an outward-wound
            // mesh, and its triangles face them.
            assert!(n.dot(*p - centre) < 0.0, "{p} {n}");
            assert!(n.dot(winding) > 0.0, "{p} {n} {winding}");
        }
    }
    // The default is three levels; bad control meshes are refused at their place.
    let text = format!("WorldBegin\nShape \"loopsubdiv\" {tet}\n");
    let c = converted(&text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(c.desc.triangles.len(), 4 * 64);
    for (shape, what) in [
        (
            "\"integer levels\" -1 \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]",
            "levels -1 must be >= 0",
        ),
        (
            "\"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 1]",
            "uses a vertex more than once",
        ),
        (
            "\"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 5]",
            "vertex index 5 is out of range",
        ),
        (
            "\"integer levels\" 40 \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]",
            "limit of 16777216",
        ),
    ] {
        let e = converted(
            &format!("WorldBegin\nShape \"loopsubdiv\" {shape}\n"),
            Files::default(),
            false,
        )
        .unwrap_err();
        assert!(e.starts_with("scene/main.pbrt:2:1: ") && e.contains(what), "{e}");
    }
}

#[test]
fn a_file_included_twice_lists_each_unsupported_place_once() {
    let files = Files::default().with(
        "scene/s.pbrt",
        "Shape \"teapot\"\nShape \"curve\" \"float alpha\" 0.5 \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]\n\
         Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]\n",
    );
    // Moving shapes: two problems on each line of s.pbrt.
    let e = converted(
        "WorldBegin\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n\
         Include \"s.pbrt\"\nInclude \"s.pbrt\"\n",
        files,
        false,
    )
    .unwrap_err();
    assert_eq!(e.matches("\"teapot\"").count(), 1, "{e}");
    assert_eq!(e.matches("a curve cut out by \"alpha\"").count(), 1, "{e}");
    assert_eq!(e.matches("a moving \"curve\" (ActiveTransform)").count(), 2, "{e}");
}

#[test]
fn mix_materials_convert_with_their_amount_and_refuse_what_they_cannot_hold() {
    let text = "WorldBegin\nMakeNamedMaterial \"a\" \"string type\" \"diffuse\" \"rgb reflectance\" [0.2 0.2 0.2]\n\
                MakeNamedMaterial \"b\" \"string type\" \"conductor\"\n\
                MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string materials\" [\"a\" \"b\"] \"float amount\" 0.25\n\
                NamedMaterial \"m\"\nShape \"sphere\"\n";
    let c = converted(text, Files::default(), false).unwrap();
    let m = c.desc.materials.iter().find(|(n, _)| n == "m").map(|(_, m)| m).unwrap();
    let crate::material::Material::Mix { materials, amount } = m else {
        panic!("{m:?}")
    };
    assert_eq!(materials[0], crate::material::Material::diffuse(0.2, 0.2, 0.2));
    assert!(matches!(materials[1], crate::material::Material::Conductor { .. }));
    assert_eq!(*amount, crate::texture::Texture::from(Vec3::splat(0.25)));
    // A part we lack makes the whole mix unsupported (grey with --lenient).
    let text = "WorldBegin\nMakeNamedMaterial \"a\" \"string type\" \"diffuse\"\n\
                MakeNamedMaterial \"h\" \"string type\" \"plastic\"\n\
                Material \"mix\" \"string materials\" [\"a\" \"h\"]\nShape \"sphere\"\n";
    let e = converted(text, Files::default(), false).unwrap_err();
    assert!(
        e.starts_with("scene/main.pbrt:4: material (mix: material \"h\": type \"plastic\" is not supported)"),
        "{e}"
    );
    // Names that are not two defined materials are errors at the parameter.
    let e = converted(
        "WorldBegin\nMaterial \"mix\" \"string materials\" [\"x\" \"y\"]\nShape \"sphere\"\n",
        Files::default(),
        true,
    )
    .unwrap_err();
    assert!(
        e.starts_with("scene/main.pbrt:2: mix: material \"x\" is not defined"),
        "{e}"
    );
    let e = converted(
        "WorldBegin\nMaterial \"mix\" \"string materials\" \"x\"\nShape \"sphere\"\n",
        Files::default(),
        true,
    )
    .unwrap_err();
    assert!(e.contains("names 1 materials, not two"), "{e}");
    let e = converted(
        "WorldBegin\nMakeNamedMaterial \"m\" \"string type\" \"mix\" \"string materials\" [\"m\" \"m\"]\n\
         NamedMaterial \"m\"\nShape \"sphere\"\n",
        Files::default(),
        true,
    )
    .unwrap_err();
    assert!(e.contains("mix: materials nest more than 16 deep (a cycle?)"), "{e}");
}

#[test]
fn a_gbuffer_film_renders_its_rgb_image_and_a_spectral_one_is_refused() {
    let rgb = converted(
        "Film \"rgb\" \"integer xresolution\" 40 \"integer yresolution\" 20\nWorldBegin\n",
        Files::default(),
        false,
    )
    .unwrap();
    let g = converted(
        "Film \"gbuffer\" \"integer xresolution\" 40 \"integer yresolution\" 20 \"string coordinatesystem\" \"world\"\nWorldBegin\n",
        Files::default(),
        false,
    )
    .unwrap();
    assert_eq!((g.desc.camera.width, g.desc.camera.height), (40, 20));
    assert_eq!(format!("{:?}", g.desc.camera), format!("{:?}", rgb.desc.camera));
    assert!(
        g.warnings
            .iter()
            .any(|w| w.contains("geometry channels are not written")),
        "{:?}",
        g.warnings
    );
    assert!(!g.warnings.iter().any(|w| w.contains("not used")), "{:?}", g.warnings);
    let e = converted("Film \"spectral\"\nWorldBegin\n", Files::default(), false).unwrap_err();
    assert!(e.contains("Film \"spectral\" is not supported"), "{e}");
}

/// A scene whose medium "smoke", of type `ty` with `params` (on line 8),
/// has three samples along x over the box [0, 3] x [0, 1] x [0, 1] of a
/// medium space moved by Translate 10 0 0 and Scale 2: in pbrt's world they
/// sit at x = 11, 13 and 15 (y = z = 1), in ours (pbrt's mirror image across
/// the camera's vertical plane) at x = -11, -13, -15.
fn placed_grid(ty: &str, params: &str) -> String {
    format!(
        "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\nAttributeBegin\n\
         Translate 10 0 0\nScale 2 2 2\n\
         MakeNamedMedium \"smoke\" \"string type\" \"{ty}\" \"integer nx\" 3 \"point3 p1\" [3 1 1]\n\
         {params}\nAttributeEnd\n\
         MediumInterface \"smoke\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 20\n"
    )
}

#[test]
fn grid_media_are_placed_where_pbrt_places_them() {
    // Three densities along x over the box [0, 3] x [0, 1] x [0, 1] of a
    // medium space moved by Translate 10 0 0 and Scale 2: in pbrt's world
    // the samples sit at x = 11, 13 and 15 (y = z = 1). Ours is pbrt's
    // mirror image across the camera's vertical plane (x -> -x here).
    let grid = |extra: &str| {
        placed_grid(
            "uniformgrid",
            &format!("\"rgb sigma_a\" [0.5 0.5 0.5] \"float scale\" 2 {extra}"),
        )
    };
    let c = converted(&grid("\"float density\" [1 5 2]"), Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    let (_, m) = &c.desc.media[0];
    assert_eq!((m.sigma_a, m.sigma_s), (Vec3::ONE, Vec3::splat(2.0)));
    let g = m.density.as_ref().expect("a density grid");
    assert_eq!(g.resolution(), Some([3, 1, 1]));
    for (x, d) in [
        (-11.0, 1.0),
        (-13.0, 5.0),
        (-15.0, 2.0),
        (-12.0, 3.0),
        (13.0, 0.0),
        (-17.5, 0.0),
    ] {
        let got = g.density(Vec3::new(x, 1.0, 1.0));
        assert!((got - d).abs() < 1e-4, "x = {x}: {got} vs {d}");
    }
    // What pbrt-v4 refuses, and what we do not render, each at its place.
    for (extra, place, what) in [
        (
            "\"float density\" [1 5]",
            ":8:",
            "2 density values for a grid of 3 x 1 x 1",
        ),
        ("", ":7:", "no \"density\" values"),
        ("\"float density\" [1 -5 2]", ":8:", "a density of -5"),
        (
            "\"float density\" [1 5 2] \"integer ny\" 0",
            ":8:",
            "\"ny\" must be at least 1",
        ),
        (
            "\"float density\" [1 5 2] \"float temperature\" [900 1200]",
            ":8:",
            "2 \"temperature\" values for a grid of 3 values",
        ),
        (
            "\"float density\" [1 5 2] \"rgb Le\" [1 1 1] \"float Lescale\" [1 2]",
            ":8:",
            "2 \"Lescale\" values for a grid of 3 values",
        ),
        (
            "\"float density\" [1 5 2] \"rgb Le\" [1 1 1] \"float temperature\" [900 1200 900]",
            ":8:",
            "both \"Le\" and \"temperature\" are given",
        ),
        (
            "\"float density\" [1 5 2] \"rgb Le\" [-1 1 1]",
            ":8:",
            "\"rgb Le\": a negative component",
        ),
        (
            "\"float density\" [1 5 2] \"float temperature\" [900 nan 900]",
            ":8:",
            "nan",
        ),
        ("\"float density\" [1 5 2] \"point3 p0\" [0 1 0]", ":8:", "is empty"),
    ] {
        refused_at(&grid(extra), place, what);
    }
}

/// `text` is refused in one line at `place` (":LINE:") of the main file,
/// saying `what`.
fn refused_at(text: &str, place: &str, what: &str) {
    let e = converted(text, Files::default(), false).unwrap_err();
    assert!(
        e.starts_with(&format!("scene/main.pbrt{place}")) && e.contains(what),
        "{e}"
    );
    assert!(!e.contains('\n'), "{e}");
}

#[test]
fn rgb_grid_media_are_read_and_placed_as_pbrt_reads_them() {
    // Three samples along x over [0, 3] x [0, 1] x [0, 1], moved by
    // Translate 10 0 0 and Scale 2: at x = -11, -13, -15 of our world.
    let grid = |params: &str| placed_grid("rgbgrid", params);
    let text = grid(
        "\"rgb sigma_a\" [1 0 0  0 2 0  0 0 3] \"rgb sigma_s\" [0.5 0.5 0.5  1 1 1  0 0 0] \"float scale\" 2 \"float g\" 0.3\n\
         \"rgb Le\" [1 1 1  4 2 1  0 0 0] \"float Lescale\" 0.5",
    );
    let c = converted(&text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    assert!(c.warnings.is_empty(), "{:?}", c.warnings);
    let m = &c.desc.media[0].1;
    assert_eq!(m.g, 0.3);
    // pbrt-v4's film sees an rgbgrid's Le 106.86 times as bright as a
    // light's of the same RGB (it does not normalise these illuminants).
    let k = super::spectrum::cie_y_integral();
    assert!((k - 106.857).abs() < 0.01, "{k}");
    for (x, sa, ss, le) in [
        (-11.0, Vec3::new(2.0, 0.0, 0.0), Vec3::splat(1.0), Vec3::splat(0.5)),
        (
            -13.0,
            Vec3::new(0.0, 4.0, 0.0),
            Vec3::splat(2.0),
            Vec3::new(2.0, 1.0, 0.5),
        ),
        (-15.0, Vec3::new(0.0, 0.0, 6.0), Vec3::ZERO, Vec3::ZERO),
        (
            -12.0,
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::splat(1.5),
            Vec3::new(1.25, 0.75, 0.5),
        ),
        (13.0, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO),
    ] {
        let p = Vec3::new(x, 1.0, 1.0);
        let (a, s) = m.coefficients_at(p);
        let close = |u: Vec3, v: Vec3| (u - v).abs().max_element() < 1e-4;
        let glow = m.le(p) / k;
        assert!(
            close(a, sa) && close(s, ss) && close(glow, le),
            "x = {x}: {a} {s} {glow}"
        );
    }
    // Without sigma_s it is one (times the scale) all over the box.
    let c = converted(&grid("\"rgb sigma_a\" [1 0 0  0 2 0  0 0 3]"), Files::default(), false).unwrap();
    assert_eq!(
        c.desc.media[0].1.coefficients_at(Vec3::new(-15.9, 0.1, 1.9)).1,
        Vec3::ONE
    );
    // pbrt-v4's errors, each at its place.
    for (params, place, what) in [
        (
            "\"float g\" 0.5",
            ":7:",
            "an rgbgrid needs \"sigma_a\" or \"sigma_s\" values",
        ),
        (
            "\"rgb sigma_s\" [1 1 1  1 1 1  1 1 1] \"rgb Le\" [1 1 1  1 1 1  1 1 1]",
            ":8:",
            "\"Le\" needs \"sigma_a\" values",
        ),
        (
            "\"rgb sigma_a\" [1 1 1  1 1 1]",
            ":8:",
            "2 \"sigma_a\" values for a grid of 3 x 1 x 1",
        ),
        (
            "\"rgb sigma_a\" [1 1 1  1 1 1  1 1 1] \"rgb sigma_s\" [1 1 1]",
            ":8:",
            "1 \"sigma_s\" values for a grid of 3 x 1 x 1",
        ),
        (
            "\"rgb sigma_a\" [1 1 1  1 1 1  1 1 1] \"rgb Le\" [1 1 1]",
            ":8:",
            "1 \"Le\" values for a grid of 3 x 1 x 1",
        ),
        (
            "\"rgb sigma_a\" [1 1 1  1 1 1  1 1 1] \"integer ny\" 0",
            ":8:",
            "\"ny\" must be at least 1",
        ),
        (
            "\"rgb sigma_a\" [1 1 1  1 1 1  1 1 1] \"point3 p0\" [0 1 0]",
            ":8:",
            "is empty",
        ),
    ] {
        refused_at(&grid(params), place, what);
    }
}

#[test]
fn emissive_media_glow_where_pbrt_makes_them_glow() {
    use super::spectrum::blackbody_film_rgb as blackbody_rgb;
    // The grid of `grid_media_are_placed_where_pbrt_places_them`: samples at
    // x = -11, -13, -15 of our world, (y, z) = (1, 1).
    let grid = |extra: &str| placed_grid("uniformgrid", &format!("\"float density\" [1 5 2] {extra}"));
    let le_at = |text: &str, x: f32| {
        let c = converted(text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
        assert!(c.warnings.is_empty(), "{:?}", c.warnings);
        c.desc.media[0].1.le(Vec3::new(x, 1.0, 1.0))
    };
    let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() <= 1e-3 * b.abs().max_element().max(1e-6);
    // Temperatures (value - offset) x scale kelvin, times Lescale.
    let t = grid(
        "\"float temperature\" [900 1200 50] \"float temperatureoffset\" 100 \"float temperaturescale\" 2 \"float Lescale\" [1 0.5 2]",
    );
    for (x, expected) in [
        (-11.0, blackbody_rgb(1600.0)),
        (-13.0, blackbody_rgb(2200.0) * 0.5),
        // Below 100 K nothing glows.
        (-15.0, Vec3::ZERO),
        (13.0, Vec3::ZERO),
    ] {
        let got = le_at(&t, x);
        assert!(close(got, expected), "x = {x}: {got} vs {expected}");
    }
    assert!(blackbody_rgb(2200.0).max_element() > 0.01);
    // "temperaturecutoff" is the offset's older name.
    let old = grid("\"float temperature\" [900 1200 50] \"float temperaturecutoff\" 100");
    assert!(close(le_at(&old, -13.0), blackbody_rgb(1100.0)));
    // Le, with pbrt-v4's default Lescale: one sample of 1 in the box's
    // middle, which its lookup fades towards the faces (two thirds of it at
    // the first density sample, a sixth of the box in).
    let le = Vec3::new(2.0, 1.0, 0.5);
    let g = grid("\"rgb Le\" [2 1 0.5]");
    assert!(close(le_at(&g, -13.0), le));
    assert!(close(le_at(&g, -11.0), le * (2.0 / 3.0)));
    // A homogeneous medium: Le times the one Lescale everywhere.
    let h =
        "WorldBegin\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"rgb Le\" [2 1 0.5] \"float Lescale\" 3\n\
             MediumInterface \"m\" \"\"\nMaterial \"interface\"\nShape \"sphere\"\n";
    assert!(close(le_at(h, 0.0), le * 3.0));
    assert!(close(le_at(h, 100.0), le * 3.0));
    // A black Le is no emission at all.
    let c = converted(&grid("\"rgb Le\" [0 0 0]"), Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    assert!(c.desc.media[0].1.emission.is_none());
}

#[test]
fn cloud_media_are_read_with_pbrts_defaults_and_place() {
    // pbrt-v4's cloud over the default box [0, 1]^3 moved by Translate 4 0 0,
    // density 1, wispiness 1, frequency 5 unless given; our world is pbrt's
    // mirrored in x here. "scale" is no parameter of a cloud.
    let text = "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\nAttributeBegin\n\
                Translate 4 0 0\nMakeNamedMedium \"c\" \"string type\" \"cloud\" \"float density\" 2\n\
                \"rgb sigma_s\" [3 3 3] \"float scale\" 7\nAttributeEnd\n\
                MediumInterface \"c\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 20\n";
    let c = converted(text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    let (_, m) = &c.desc.media[0];
    assert_eq!((m.sigma_a, m.sigma_s), (Vec3::ONE, Vec3::splat(3.0)));
    assert!(
        c.warnings.iter().any(|w| w.contains("\"float scale\" is not used")),
        "{:?}",
        c.warnings
    );
    let d = m.density.as_ref().expect("a cloud");
    assert_eq!(d.resolution(), None);
    let expected = crate::medium::Density::cloud(2.0, 1.0, 5.0, Vec3::ZERO, Vec3::ONE, Mat4::IDENTITY).unwrap();
    for p in [
        Vec3::new(0.2, 0.6, 0.3),
        Vec3::new(0.7, 0.9, 0.8),
        Vec3::new(0.5, 0.3, 0.1),
    ] {
        let ours = d.density(Vec3::new(-(4.0 + p.x), p.y, p.z));
        assert_eq!(ours, expected.density(p), "{p}");
    }
    assert_eq!(d.density(Vec3::new(4.5, 0.5, 0.5)), 0.0);
}

#[test]
fn media_are_read_with_their_boundaries_oriented_as_pbrt_orients_them() {
    use crate::material::Material;
    use crate::medium::{Medium, MediumInterface};
    use crate::scene::{Boundary, CutShapes};
    let text = "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.2 0.3]\n\
                  \"rgb sigma_s\" [1 2 3] \"float scale\" 2 \"float g\" 0.25\n\
                MakeNamedMedium \"unused\" \"string type\" \"homogeneous\"\n\
                MediumInterface \"\" \"fog\"\nCamera \"perspective\"\nWorldBegin\nMediumInterface \"\" \"\"\n\
                AttributeBegin\nMediumInterface \"fog\" \"\"\nMaterial \"interface\"\nShape \"sphere\"\n\
                Material \"diffuse\"\nReverseOrientation\nShape \"sphere\" \"float radius\" 2\nAttributeEnd\n\
                AttributeBegin\nMediumInterface \"fog\" \"\"\n\
                Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n\
                Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n\
                  \"normal N\" [0 0 -1 0 0 -1 0 0 -1]\nAttributeEnd\n\
                Shape \"sphere\" \"float radius\" 5\n";
    let c = converted(text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    let d = &c.desc;
    // Only the media named somewhere are kept.
    let fog = Medium {
        sigma_a: Vec3::new(0.2, 0.4, 0.6),
        sigma_s: Vec3::new(2.0, 4.0, 6.0),
        g: 0.25,
        density: None,
        emission: None,
    };
    assert_eq!(d.media, [("fog".to_string(), fog)]);
    assert_eq!(d.camera_medium, Some(0));
    let inside = MediumInterface {
        inside: Some(0),
        outside: None,
    };
    // The first sphere has no surface; the second is turned inside out; the
    // second triangle's normals face away from its winding, so it is wound
    // the other way (its geometric normal on pbrt-v4's side) and bounds the
    // fog as the first does; the last sphere is in no medium's boundary.
    let expected = [
        Boundary {
            interface: inside,
            shapes: CutShapes::Sphere(0),
        },
        Boundary {
            interface: inside.flipped(),
            shapes: CutShapes::Sphere(1),
        },
        Boundary {
            interface: inside,
            shapes: CutShapes::Triangles(0..1),
        },
        Boundary {
            interface: inside,
            shapes: CutShapes::Triangles(1..2),
        },
    ];
    assert_eq!(d.boundaries, expected);
    let [p0, p1, p2] = d.triangles.vertices(1).unwrap();
    assert!((p1 - p0).cross(p2 - p0).z < 0.0);
    assert_eq!(d.materials[d.spheres[0].material as usize].1, Material::Interface);
    assert_ne!(d.materials[d.spheres[1].material as usize].1, Material::Interface);
    assert_eq!(d.spheres.len(), 3);
    // pbrt-v4's default integrator renders media; its "path" would not.
    let ignored = |c: &convert::Converted| c.warnings.iter().any(|w| w.contains("ignores participating media"));
    assert!(!ignored(&c), "{:?}", c.warnings);
    let c = converted(&format!("Integrator \"path\"\n{text}"), Files::default(), false).unwrap();
    assert!(ignored(&c), "{:?}", c.warnings);
    // Our bidirectional path tracer has no media: the path tracer renders them.
    let integrator = |c: &convert::Converted| c.desc.settings.scene_file.get("integrator").map(|v| v.0);
    let c = converted(&format!("Integrator \"bdpt\"\n{text}"), Files::default(), false).unwrap();
    assert_eq!(integrator(&c), Some(Value::Name("path")));
    assert!(
        c.warnings.iter().any(|w| w.contains("bdpt") && w.contains("media")),
        "{:?}",
        c.warnings
    );
    let plain = "Integrator \"bdpt\" \"integer maxdepth\" 7\nWorldBegin\nLightSource \"point\"\nShape \"sphere\"\n";
    let c = converted(plain, Files::default(), false).unwrap();
    assert_eq!(integrator(&c), Some(Value::Name("bdpt")));
    assert_eq!(
        c.desc.settings.scene_file.get("max_depth").map(|v| v.0),
        Some(Value::Int(7))
    );
}

#[test]
fn triangles_are_wound_to_face_pbrts_surface_normal() {
    // pbrt-v4's surface normal says which side of a dielectric is inside:
    // the vertex normals' side when a mesh has them (pbrt-v4 takes them as
    // authoritative, turned by ReverseOrientation), else the winding's,
    // turned by ReverseOrientation and by a transformation that swaps
    // handedness. Ours is the geometric normal: triangles are wound to it.
    let quad = |extra: &str| {
        format!(
            "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 1 1 0 0 1 0] \"integer indices\" [0 1 2 0 2 3] {extra}\n"
        )
    };
    let away = "\"normal N\" [0 0 -1 0 0 -1 0 0 -1 0 0 -1]";
    let text = format!(
        "WorldBegin\nMaterial \"dielectric\"\n{}{}AttributeBegin\nReverseOrientation\n{}{}AttributeEnd\n\
         AttributeBegin\nScale 1 1 -1\n{}AttributeEnd\n",
        quad(""),
        quad(away),
        quad(""),
        quad(away),
        quad(""),
    );
    let c = converted(&text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    let z: Vec<f32> = c
        .desc
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.vertices;
            (b - a).cross(c - a).normalize().z
        })
        .collect();
    // The plain quad faces +z; its normals turn it; ReverseOrientation turns
    // the bare quad and turns the normals back; the mirror turns it.
    let want = [1.0, 1.0, -1.0, -1.0, -1.0, -1.0, 1.0, 1.0, -1.0, -1.0];
    for (i, (z, w)) in z.iter().zip(want).enumerate() {
        assert!((z - w).abs() < 1e-6, "triangle {i}: {z:?}");
    }
    // Normals and texture coordinates go with their vertices.
    let t = &c.desc.triangles.get(2).unwrap();
    assert_eq!(t.normals, Some([Vec3::NEG_Z; 3]));
}

/// The centre pixel of a render of an emissive wall (radiance 1) at z = 10
/// seen from the origin through a sphere of radius 1 at z = 5, its
/// `MediumInterface` and orientation as given, in a medium that absorbs
/// 0.1, 0.3 and 0.6 a unit.
fn seen_through_ink(interface: &str, reverse: bool) -> Vec3 {
    use crate::integrator::{render, IntegratorKind, RenderSettings};
    let text = format!(
        "Film \"rgb\" \"integer xresolution\" 3 \"integer yresolution\" 3\nCamera \"perspective\" \"float fov\" 2\n\
         WorldBegin\nMakeNamedMedium \"ink\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.3 0.6]\n\
           \"rgb sigma_s\" [0 0 0]\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\n\
         Shape \"trianglemesh\" \"point3 P\" [-9 -9 10 -9 9 10 9 9 10 9 -9 10] \"integer indices\" [0 1 2 0 2 3]\n\
         AttributeEnd\nAttributeBegin\nTranslate 0 0 5\nMediumInterface {interface}\nMaterial \"interface\"\n{}\
         Shape \"sphere\"\nAttributeEnd\n",
        if reverse { "ReverseOrientation\n" } else { "" }
    );
    let c = converted(&text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    let scene = crate::Scene::build(c.desc).unwrap();
    let settings = RenderSettings {
        integrator: IntegratorKind::Path,
        spp: 4,
        ..RenderSettings::default()
    };
    let film = render(&scene, &settings, &|| {}).unwrap().film;
    film.mean(1, 1, 2, 2)
}

#[test]
fn a_sphere_of_ink_darkens_what_is_seen_through_it_by_beers_law() {
    let sigma = Vec3::new(0.1, 0.3, 0.6);
    // Inside the sphere (its normal outwards, or turned in with the sides
    // swapped): the diameter, 2. Outside it instead: from the sphere to the
    // wall, 4.
    for (interface, reverse, length) in [
        ("\"ink\" \"\"", false, 2.0),
        ("\"\" \"ink\"", true, 2.0),
        ("\"\" \"ink\"", false, 4.0),
    ] {
        let l = seen_through_ink(interface, reverse);
        let expected = (-sigma * length).exp();
        assert!(
            (l / expected - 1.0).abs().max_element() < 5e-3,
            "{interface} reversed {reverse}: {l} vs {expected}"
        );
    }
}

#[test]
fn nanovdb_media_are_read_from_their_file_and_placed() {
    let fixture = include_bytes!("../../../tests/data/small-zip.nvdb");
    let scene = |params: &str| {
        format!(
            "WorldBegin\nAttributeBegin\nTranslate 1 0 0\nMakeNamedMedium \"m\" \"string type\" \"nanovdb\" {params}\n\
             MediumInterface \"m\" \"\"\nShape \"sphere\" \"float radius\" 9\nAttributeEnd\n"
        )
    };
    let files = || Files::default().with("scene/vdb/smoke.nvdb", fixture);
    let c = converted(
        &scene("\"string filename\" \"vdb/smoke.nvdb\" \"float scale\" 2 \"float Lescale\" 0.5"),
        files(),
        false,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let m = &c.desc.media[0].1;
    assert_eq!(m.sigma_a, Vec3::splat(2.0));
    let d = m.density.as_ref().unwrap();
    // NanoVDB's own sampler gave 0.12999998 at (1.3, 0.3, 1.1) of the
    // grid's space, here moved by one along x, and the scene seen in the
    // mirror that turns pbrt-v4's left-handed camera space (x -> -x).
    assert!((d.density(Vec3::new(-2.3, 0.3, 1.1)) - 0.13).abs() < 1e-5);
    assert!((d.density(Vec3::new(-1.3, 0.3, 1.1)) - 0.13).abs() > 0.01);
    // The file's temperature grid glows (500 to 1000 K: dimly red).
    let e = m.emission.as_ref().unwrap();
    assert!(e.summary().contains("blackbody"), "{}", e.summary());
    // Without a temperature grid of that name, or with Lescale 0, no glow.
    for extra in ["\"string temperaturename\" \"heat\"", "\"float Lescale\" 0"] {
        let c = converted(
            &scene(&format!("\"string filename\" \"vdb/smoke.nvdb\" {extra}")),
            files(),
            false,
        )
        .unwrap();
        assert!(c.desc.media[0].1.emission.is_none(), "{extra}");
    }
    for (params, what) in [
        (
            "\"string filename\" \"vdb/none.nvdb\"",
            "nanovdb \"vdb/none.nvdb\": cannot",
        ),
        ("", "no file name given"),
        (
            "\"string filename\" \"vdb/smoke.nvdb\" \"string gridname\" \"smoke\"",
            "no grid named \"smoke\"",
        ),
        ("\"string filename\" \"scene.txt\"", "not a NanoVDB file"),
    ] {
        let files = files().with("scene/scene.txt", "a text file, long enough for a header");
        let e = converted(&scene(params), files, false).unwrap_err();
        assert!(e.starts_with("scene/main.pbrt:4:") && e.contains(what), "{params}: {e}");
        assert!(!e.contains('\n'), "{e}");
    }
    // A file we cannot read but pbrt-v4 might (BLOSC): refused as not
    // supported; with --lenient, vacuum.
    let mut blosc = fixture.to_vec();
    blosc[14] = 2;
    let files = || Files::default().with("scene/vdb/smoke.nvdb", &blosc);
    let params = scene("\"string filename\" \"vdb/smoke.nvdb\"");
    let e = converted(&params, files(), false).unwrap_err();
    assert!(e.contains("BLOSC-compressed grids are not supported"), "{e}");
    let c = converted(&params, files(), true).unwrap();
    assert!(c.desc.media.is_empty());
}

#[test]
fn media_it_cannot_render_are_refused_at_their_place() {
    let medium = |params: &str| {
        format!(
            "WorldBegin\nMakeNamedMedium \"m\" {params}\nAttributeBegin\nMediumInterface \"m\" \"\"\nShape \"sphere\"\nAttributeEnd\n"
        )
    };
    for (params, what) in [
        (
            "\"string type\" \"openvdb\" \"string filename\" \"smoke.vdb\"",
            "media of type \"openvdb\" are not supported",
        ),
        (
            "\"string type\" \"homogeneous\" \"spectrum Le\" \"metal-Cu-eta\"",
            "\"Le\" given as this spectrum is not supported",
        ),
    ] {
        let e = converted(&medium(params), Files::default(), false).unwrap_err();
        assert!(
            e.contains("scene/main.pbrt:2: MakeNamedMedium \"m\": ") && e.contains(what),
            "{e}"
        );
        assert!(!e.contains('\n'), "{e}");
        // Lenient: vacuum instead.
        let c = converted(&medium(params), Files::default(), true).unwrap();
        assert!(c.desc.media.is_empty() && c.desc.boundaries.is_empty());
    }
    let e = converted(
        "WorldBegin\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"float g\" 1\nMediumInterface \"m\" \"\"\nShape \"sphere\"\n",
        Files::default(),
        false,
    )
    .unwrap_err();
    assert!(
        e.starts_with("scene/main.pbrt:2: MakeNamedMedium \"m\": g 1 must lie strictly between -1 and 1"),
        "{e}"
    );
    let e = converted(
        "WorldBegin\nMediumInterface \"nowhere\" \"\"\nShape \"sphere\"\n",
        Files::default(),
        false,
    )
    .unwrap_err();
    assert!(
        e.starts_with("scene/main.pbrt:3: medium \"nowhere\" is not defined"),
        "{e}"
    );
}

#[test]
fn curves_convert_into_pieces_where_pbrt_puts_them() {
    use crate::material::Material;
    use crate::math::Ray;
    let text =
        "WorldBegin\nMakeNamedMaterial \"h\" \"string type\" \"hair\" \"float eumelanin\" 2\nNamedMaterial \"h\"\n\
                AttributeBegin\nTranslate 0 0 5\nScale 2 2 2\n\
                Shape \"curve\" \"string basis\" \"bspline\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0]\n\
                  \"float width0\" 0.1 \"float width1\" 0.05 \"string type\" \"cylinder\" \"integer splitdepth\" 1\n\
                AttributeEnd\n";
    let c = converted(text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    // Two B-spline spans, each in two pieces; widths scaled by 2 and
    // tapering along the curve as pbrt-v4 lerps them.
    let curves = &c.desc.curves;
    assert_eq!(curves.len(), 4);
    assert_eq!(curves[0].curve.u, [0.0, 0.5]);
    assert!((curves[0].curve.width[0] - 0.2).abs() < 1e-6 && (curves[0].curve.width[1] - 0.15).abs() < 1e-6);
    assert!((curves[3].curve.width[1] - 0.1).abs() < 1e-6);
    let (_, m) = &c.desc.materials[curves[0].material as usize];
    let Material::Hair {
        sigma_a, eta, beta_m, ..
    } = m
    else {
        panic!("{m:?}")
    };
    assert_eq!(
        (*sigma_a, *eta, *beta_m),
        (crate::bsdf::HairBxdf::sigma_a_from_concentration(2.0, 0.0), 1.55, 0.3)
    );
    // pbrt-v4's curve runs from x = 2 to 6 at z = 5 (the spans start at
    // (p0 + 4 p1 + p2) / 6), 0.2 to 0.1 wide: the camera sees it to its
    // right. Ours is mirrored across the camera's vertical plane (x -> -x)
    // with the rest of the scene, so the same picture comes out.
    let scene = crate::Scene::build(c.desc).unwrap();
    let hit = |x: f32, y: f32| scene.intersect(&Ray::new(Vec3::new(x, y, 0.0), Vec3::Z), 0.0, f32::INFINITY);
    let h = hit(-3.0, 0.0).unwrap();
    assert!(
        (h.t - 5.0).abs() < 1e-3 && h.kind == crate::scene::PrimKind::Curve,
        "{h:?}"
    );
    assert!((h.uv.y - 0.5).abs() < 0.01, "{h:?}");
    assert!(hit(-5.9, 0.04).is_some() && hit(-5.9, 0.06).is_none());
    assert!(hit(-2.1, 0.09).is_some() && hit(-2.1, 0.11).is_none());
    assert!(hit(-6.1, 0.0).is_none() && hit(-1.9, 0.0).is_none() && hit(3.0, 0.0).is_none());
}

#[test]
fn ribbons_face_where_their_normals_say() {
    use crate::math::Ray;
    // A ribbon from x = 0 to 6 at z = 5, 1 wide, facing the camera (-z) at
    // its start and turned a quarter about x, edge on, at its end. Ours is
    // mirrored across the camera's vertical plane (x -> -x), as the rest
    // of the scene is.
    let text = "WorldBegin\nAttributeBegin\nTranslate 0 0 5\nScale 2 2 2\n\
                Shape \"curve\" \"string type\" \"ribbon\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]\n\
                  \"float width\" 0.5 \"normal N\" [0 0 -3 0 2 0]\n\
                AttributeEnd\n";
    let c = converted(text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    let scene = crate::Scene::build(c.desc).unwrap();
    let hit = |x: f32, y: f32| scene.intersect(&Ray::new(Vec3::new(x, y, 0.0), Vec3::Z), 0.0, f32::INFINITY);
    // Near its start it is as wide as given; a third of the way along its
    // normal has turned by 30 degrees, and it looks cos 30 as wide.
    assert!(hit(-0.1, 0.49).is_some() && hit(-0.1, 0.51).is_none());
    let h = hit(-2.0, 0.0).unwrap();
    assert!(
        (h.t - 5.0).abs() < 1e-3 && h.kind == crate::scene::PrimKind::Curve,
        "{h:?}"
    );
    assert!(h.ng.dot(Vec3::new(0.0, 0.5, -(0.75f32.sqrt()))).abs() > 0.9999, "{h:?}");
    let half = 0.5 * 30f32.to_radians().cos();
    assert!(hit(-2.0, half - 0.01).is_some() && hit(-2.0, half + 0.01).is_none());
    // Near its end it is nearly edge on: a thread.
    assert!(hit(-5.9, 0.0).is_some() && hit(-5.9, 0.05).is_none());
}

#[test]
fn malformed_curves_are_errors_at_their_place() {
    for (shape, what) in [
        (
            "\"integer degree\" 4 \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0]",
            "degree 4",
        ),
        ("\"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0]", "5 control points"),
        (
            "\"string basis\" \"catmullrom\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]",
            "basis \"catmullrom\"",
        ),
        ("\"float width\" 0 \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]", "widths 0"),
        (
            "\"integer splitdepth\" 40 \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]",
            "splitdepth 40",
        ),
    ] {
        let e = converted(
            &format!("WorldBegin\nShape \"curve\" {shape}\n"),
            Files::default(),
            false,
        )
        .unwrap_err();
        assert!(e.starts_with("scene/main.pbrt:2:1: curve: ") && e.contains(what), "{e}");
    }
    // 16,400 B-spline spans of 1,024 pieces each: refused before they are made.
    let points: String = (0..16_403).map(|i| format!("{i} 0 0 ")).collect();
    let many = format!(
        "WorldBegin\nShape \"curve\" \"string basis\" \"bspline\" \"integer splitdepth\" 10 \"point3 P\" [{points}]\n"
    );
    let e = converted(&many, Files::default(), false).unwrap_err();
    assert!(
        e.starts_with("scene/main.pbrt:2: curve: 16400 segments of 1024 pieces") && e.contains("limit of 16777216"),
        "{e}"
    );
    // A ribbon needs a normal at each segment's end, each with a direction,
    // and no two neighbours opposite.
    for (normals, what) in [
        ("", "needs 2 normals \"N\" (one at each segment's end), not 0"),
        ("\"normal N\" [0 0 1 0 0 1 0 0 1]", "needs 2 normals"),
        (
            "\"normal N\" [0 0 1 0 0 0]",
            "normal 1 of \"N\", [0, 0, 0], has no direction",
        ),
        (
            "\"normal N\" [0 0 1 0 0 -1]",
            "normals 0 and 1 of \"N\" point opposite ways",
        ),
    ] {
        let ribbon = format!(
            "WorldBegin\nShape \"curve\" \"string type\" \"ribbon\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] {normals}\n"
        );
        let e = converted(&ribbon, Files::default(), false).unwrap_err();
        assert!(e.starts_with("scene/main.pbrt:2:1: curve: ") && e.contains(what), "{e}");
    }
    // Huge components keep their direction.
    let huge = "WorldBegin\nShape \"curve\" \"string type\" \"ribbon\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] \
                \"normal N\" [0 0 3e38 0 3e38 0]\n";
    let c = converted(huge, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    let n = c.desc.curves[0].curve.n;
    assert!(n[0].z.abs() > 0.999 && n[1].y.abs() > 0.999, "{n:?}");
    // An area light on a curve cannot be sampled (pbrt-v4 cannot either).
    let lit = "WorldBegin\nAreaLightSource \"diffuse\"\nShape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]\n";
    let e = converted(lit, Files::default(), false).unwrap_err();
    assert!(e.contains("an area light on a curve"), "{e}");
}

/// The mean radiance seen through 16 x 16 pixels of a tangle of hair of
/// absorption `sigma_a` (pbrt-v4 syntax) in a uniform white environment.
fn hair_in_a_furnace(sigma_a: &str, integrator: crate::integrator::IntegratorKind) -> Vec3 {
    use crate::integrator::{render, RenderSettings};
    let mut text = format!(
        "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\nCamera \"perspective\" \"float fov\" 10\n\
         WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n\
         Material \"hair\" {sigma_a} \"float beta_m\" 0.25 \"float beta_n\" 0.4\nTranslate 0 0 10\n"
    );
    // Wavy strands across the view, in front of one another.
    let mut rng = crate::sampling::Rng::new(3, 4);
    for i in 0..120 {
        let (y, z) = (-0.9 + 1.8 * rng.next_f32(), 0.3 * (i as f32 / 120.0) - 0.15);
        let mut wave = |k: f32| 0.2 * (k + 7.0 * rng.next_f32()).sin();
        text += &format!(
            "Shape \"curve\" \"string type\" \"cylinder\" \"string basis\" \"bspline\" \"float width\" 0.04\n\
             \"point3 P\" [-2 {} {z} -1 {} {z} 0 {} {z} 1 {} {z} 2 {} {z}]\n",
            y + wave(0.0),
            y + wave(1.0),
            y + wave(2.0),
            y + wave(3.0),
            y + wave(4.0)
        );
    }
    let c = converted(&text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    let scene = crate::Scene::build(c.desc).unwrap();
    let settings = RenderSettings {
        integrator,
        spp: 64,
        ..RenderSettings::default()
    };
    let film = render(&scene, &settings, &|| {}).unwrap().film;
    film.mean(0, 0, 16, 16)
}

#[test]
fn hair_that_absorbs_nothing_in_a_white_furnace_is_as_bright_as_the_furnace() {
    use crate::integrator::IntegratorKind;
    // Every path ends in the environment of radiance 1 and the fibres keep
    // all the light: the picture is 1 wherever hair is, however many times
    // light scatters between strands. Leaking light at a fibre's sides (its
    // glossy transmission refused, a ray meeting its own fibre) would darken it.
    for integrator in [IntegratorKind::Path, IntegratorKind::Bdpt] {
        let l = hair_in_a_furnace("\"rgb sigma_a\" [0 0 0]", integrator);
        assert!((l - Vec3::ONE).abs().max_element() < 0.02, "{integrator:?}: {l}");
    }
    // Brown hair absorbs, blue most.
    let l = hair_in_a_furnace("\"float eumelanin\" 1.3", IntegratorKind::Path);
    assert!(l.x < 0.9 && l.x > l.y && l.y > l.z, "{l}");
}

#[test]
fn cylinders_are_meshes_where_pbrts_quadric_is() {
    use crate::math::Ray;
    // pbrt-v4's cylinder of radius 0.5 about the world's y axis (object z,
    // turned by the rotation) through (0, 0, 5), the half of it beyond z = 5
    // (phi from object x to 180 degrees: object y is world z). Ours is
    // mirrored x -> -x with the rest of the scene.
    let text = "WorldBegin\nTranslate 0 0 5\nRotate 90 1 0 0\n\
                Shape \"cylinder\" \"float radius\" 0.5 \"float phimax\" 180\n";
    let c = converted(text, Files::default(), false).unwrap_or_else(|e| panic!("{e}"));
    let scene = crate::Scene::build(c.desc).unwrap();
    let hit = |x: f32, y: f32| scene.intersect(&Ray::new(Vec3::new(x, y, 0.0), Vec3::Z), 0.0, f32::INFINITY);
    // Through the open near half to the far one, seen from inside.
    let h = hit(-0.2, 0.0).unwrap();
    let z = 5.0 + (0.25f32 - 0.04).sqrt();
    assert!((h.t - z).abs() < 1e-4, "{h:?}");
    assert!(h.ng.z > 0.9 && h.ns.dot(h.ng) > 0.99, "outward: {h:?}");
    // u = phi / 180 degrees (phi = atan2(0.458, 0.2)), v = (z + 1) / 2 with object z = -world y.
    let u = (z - 5.0).atan2(0.2).to_degrees() / 180.0;
    assert!(
        (h.uv.x - u).abs() < 1e-3 && (h.uv.y - 0.5).abs() < 1e-4,
        "{h:?} against u {u}"
    );
    assert!((hit(-0.2, 0.6).unwrap().uv.y - 0.2).abs() < 1e-4);
    assert!(hit(-0.2, 0.99).is_some() && hit(-0.2, 1.01).is_none() && hit(-0.55, 0.0).is_none());
}

#[test]
fn measured_presets_give_media_their_coefficients_times_scale() {
    let text = "WorldBegin\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"string preset\" \"Wholemilk\" \"float scale\" 10\n\
                MediumInterface \"m\" \"\"\nShape \"sphere\"\n";
    let c = converted(text, Files::default(), false).unwrap();
    let m = &c.desc.media[0].1;
    assert!(
        (m.sigma_a - Vec3::new(0.011, 0.024, 0.14)).abs().max_element() < 1e-6,
        "{:?}",
        m.sigma_a
    );
    assert!(
        (m.sigma_s - Vec3::new(25.5, 32.1, 37.7)).abs().max_element() < 1e-4,
        "{:?}",
        m.sigma_s
    );
    // An unknown name is the file's error at the parameter, lenient or not.
    for lenient in [false, true] {
        let e = converted(&text.replace("Wholemilk", "Wholemilk2"), Files::default(), lenient).unwrap_err();
        assert!(
            e.starts_with("scene/main.pbrt:2:") && e.contains("no measured medium is named \"Wholemilk2\""),
            "{e}"
        );
    }
}

#[test]
fn subsurface_materials_read_every_way_pbrt_gives_their_medium() {
    use crate::material::{Material, SubsurfaceScattering};
    let material = |params: &str| {
        let text = format!(
            "WorldBegin\nTexture \"t\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [ 1 2 3 ]\n\
             Material \"subsurface\" {params}\nShape \"sphere\"\n"
        );
        let c = converted(&text, Files::default(), false)?;
        let Some((_, Material::Subsurface(s))) = c.desc.materials.last() else {
            panic!("{:?}", c.desc.materials)
        };
        Ok::<_, String>(s.as_ref().clone())
    };
    // By name: a measured medium in mm^-1 times scale, g forced to 0.
    let s = material("\"string name\" \"Skin1\" \"float scale\" 50 \"float eta\" 1.5 \"float g\" 0.5").unwrap();
    assert_eq!(s.eta, 1.5);
    assert_eq!(*s.table, crate::bssrdf::BssrdfTable::new(0.0, 1.5));
    let constant = |t: &crate::texture::Texture| match t {
        crate::texture::Texture::Constant(c) => *c,
        other => panic!("{other:?}"),
    };
    let SubsurfaceScattering::Coefficients { sigma_a, sigma_s } = &s.scattering else {
        panic!()
    };
    let (sigma_a, sigma_s) = (constant(sigma_a), constant(sigma_s));
    assert!(
        (sigma_a - Vec3::new(1.6, 8.5, 24.0)).abs().max_element() < 1e-4,
        "{sigma_a:?}"
    );
    assert!(
        (sigma_s - Vec3::new(37.0, 44.0, 50.5)).abs().max_element() < 1e-4,
        "{sigma_s:?}"
    );
    // By coefficients, with g kept and eta 1.33 by default.
    let s = material("\"rgb sigma_a\" [ 1 2 3 ] \"rgb sigma_s\" [ 4 5 6 ] \"float g\" 0.3 \"float scale\" 2").unwrap();
    assert_eq!(*s.table, crate::bssrdf::BssrdfTable::new(0.3, 1.33));
    assert_eq!(
        s.scattering,
        SubsurfaceScattering::Coefficients {
            sigma_a: Vec3::new(2.0, 4.0, 6.0).into(),
            sigma_s: Vec3::new(8.0, 10.0, 12.0).into()
        }
    );
    // By reflectance and mean free path (1 unless given), times scale.
    let s = material("\"rgb reflectance\" [ 0.8 0.5 0.2 ] \"float scale\" 0.1").unwrap();
    let SubsurfaceScattering::Reflectance { reflectance, mfp } = &s.scattering else {
        panic!()
    };
    assert_eq!(*reflectance, crate::texture::Texture::from(Vec3::new(0.8, 0.5, 0.2)));
    assert_eq!(*mfp, Vec3::splat(0.1).into());
    // Nothing said: pbrt-v4's default, whole milk per unit length.
    let s = material("").unwrap();
    let SubsurfaceScattering::Coefficients { sigma_s, .. } = &s.scattering else {
        panic!()
    };
    assert_eq!(constant(sigma_s), Vec3::new(2.55, 3.21, 3.77));
    // Textures: a coefficient's is scaled, wrapped.
    let s = material("\"texture sigma_a\" \"t\" \"rgb sigma_s\" [ 4 5 6 ] \"float scale\" 2");
    let s = s.unwrap();
    let SubsurfaceScattering::Coefficients { sigma_a, sigma_s } = &s.scattering else {
        panic!()
    };
    assert!(matches!(sigma_a, crate::texture::Texture::Scale { .. }), "{sigma_a:?}");
    assert_eq!(constant(sigma_s), Vec3::new(8.0, 10.0, 12.0));
    // Mistakes are the file's errors at their place.
    let e = material("\"string name\" \"Skin3\"").unwrap_err();
    assert!(
        e.starts_with("scene/main.pbrt:3:") && e.contains("no measured medium is named \"Skin3\""),
        "{e}"
    );
    let e = material("\"rgb sigma_a\" [ 1 2 3 ]").unwrap_err();
    assert!(e.contains("\"sigma_a\" given without \"sigma_s\""), "{e}");
    let e = material("\"float eta\" -1").unwrap_err();
    assert!(e.contains("subsurface: \"eta\" -1 must be a positive number"), "{e}");
}

#[test]
fn lights_at_infinity_take_only_the_turn_of_their_transformation() {
    // sssdragon's sky: a rotation whose matrix also holds a projective row,
    // which pbrt-v4's direction transforms leave out.
    let text = |t: &str| {
        format!("WorldBegin\nAttributeBegin\n{t}\nLightSource \"infinite\" \"rgb L\" [ 1 1 1 ]\nAttributeEnd\nShape \"sphere\"\n")
    };
    let sky = "ConcatTransform [ -0.224951 0 -0.97437 0 -0.97437 0 0.224951 0 0 1 0 8.87 0 0 0 1 ]";
    let c = converted(&text(sky), Files::default(), false).unwrap();
    assert_eq!(c.desc.lights.len(), 1);
    let c = converted(
        &text("Translate 1 2 3\nRotate 30 0 0 1\nScale 2 2 2"),
        Files::default(),
        false,
    )
    .unwrap();
    assert_eq!(c.desc.lights.len(), 1);
    let e = converted(&text("Scale 1 2 1"), Files::default(), false).unwrap_err();
    assert!(
        e.starts_with("scene/main.pbrt:4: infinite: a transformation other than rotation and uniform scale"),
        "{e}"
    );
}

#[test]
fn motion_with_media_is_refused_at_the_moving_shape() {
    let text = "WorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n\
                AttributeBegin\nActiveTransform EndTime\nTranslate 1 0 0\nActiveTransform All\n\
                Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\nAttributeEnd\n\
                AttributeBegin\nMediumInterface \"fog\" \"\"\nMaterial \"interface\"\nShape \"sphere\"\nAttributeEnd\n";
    let e = converted(text, Files::default(), false).unwrap_err();
    assert!(
        e.starts_with("scene/main.pbrt:7: motion (ActiveTransform) in a scene with participating media"),
        "{e}"
    );
    let c = converted(text, Files::default(), true).unwrap_or_else(|e| panic!("{e}"));
    assert!(c.desc.moving.is_empty() && !c.desc.media.is_empty());
}

#[test]
fn emitters_keep_a_material_that_reflects() {
    use crate::light::Light;
    use crate::material::Material;
    // pbrt-v4's emitting shapes reflect by their material; one of black
    // diffuse reflectance (how emitters that only emit are written) does not.
    let text = "WorldBegin\nTexture \"t\" \"spectrum\" \"checkerboard\"\n\
         AttributeBegin\nAreaLightSource \"diffuse\"\nShape \"sphere\"\nAttributeEnd\n\
         AttributeBegin\nMaterial \"diffuse\" \"rgb reflectance\" [0 0 0]\nAreaLightSource \"diffuse\"\nShape \"disk\"\nAttributeEnd\n\
         AttributeBegin\nMaterial \"diffuse\" \"texture reflectance\" \"t\"\nAreaLightSource \"diffuse\"\nShape \"disk\"\nAttributeEnd\n\
         AttributeBegin\nMaterial \"conductor\"\nAreaLightSource \"diffuse\"\nTranslate 0 0 3\n\
         Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2] \"point2 uv\" [0.1 0.2 0.3 0.4 0.5 0.6]\n\
         AttributeEnd\n";
    let c = converted(text, Files::default(), false).unwrap();
    let d = &c.desc;
    assert_eq!(d.lights.len(), 4);
    let name = |i: usize| {
        d.light_surfaces
            .get(i)
            .cloned()
            .flatten()
            .map(|s| d.materials[s.material as usize].1.clone())
    };
    assert!(matches!(name(0), Some(Material::Diffuse { .. })), "{:?}", name(0));
    assert_eq!(name(1), None);
    assert!(matches!(name(2), Some(Material::Diffuse { .. })), "{:?}", name(2));
    assert!(matches!(name(3), Some(Material::Conductor { .. })), "{:?}", name(3));
    // The triangle's texture coordinates stay with their vertices, which the
    // scene's reflection turns as it turns the light's.
    let (Some(Some(s)), Light::Triangle { vertices, .. }) = (d.light_surfaces.get(3), &d.lights[3]) else {
        panic!("{:?}", d.lights[3])
    };
    let uvs = s.uvs.unwrap();
    for (uv, p) in uvs.iter().zip(vertices) {
        let at = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
            .iter()
            .position(|&(x, y)| (p.x.abs() - x).abs() < 1e-5 && (p.y - y).abs() < 1e-5)
            .unwrap();
        let want = [Vec2::new(0.1, 0.2), Vec2::new(0.3, 0.4), Vec2::new(0.5, 0.6)][at];
        assert!((*uv - want).length() < 1e-6, "{uv} at {p}, want {want}");
    }
    assert!(!c.warnings.iter().any(|w| w.contains("reflect")), "{:?}", c.warnings);
    // A glass emitter that bounds a medium reflects nothing, with a
    // warning; a bumped one reflects, its bump not applied, with a warning.
    let text = "WorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n\
         AttributeBegin\nMaterial \"dielectric\"\nMediumInterface \"fog\" \"\"\nAreaLightSource \"diffuse\"\nShape \"sphere\"\nAttributeEnd\n\
         AttributeBegin\nMaterial \"diffuse\" \"float displacement\" 0.1\nAreaLightSource \"diffuse\"\nShape \"disk\"\nAttributeEnd\n";
    let c = converted(text, Files::default(), false).unwrap();
    assert_eq!(c.desc.lights.len(), 2);
    assert_eq!(c.desc.light_surfaces.first().cloned().flatten(), None);
    assert!(
        matches!(c.desc.light_surfaces.get(1), Some(Some(_))),
        "{:?}",
        c.desc.light_surfaces
    );
    for w in [
        "1 emitting shapes bound a medium",
        "1 emitting shapes have a bump or normal map",
    ] {
        assert!(c.warnings.iter().any(|x| x.contains(w)), "{w}: {:?}", c.warnings);
    }
}

#[test]
fn measured_materials_read_their_file_and_name_bad_ones_at_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.bsdf");
    std::fs::write(&good, crate::bsdf::measured_test_file()).unwrap();
    let bad = dir.path().join("bad.bsdf");
    std::fs::write(&bad, "not a tensor").unwrap();
    let scene = |material: &str| {
        format!(
            "WorldBegin\nMakeNamedMaterial \"a\" \"string type\" \"diffuse\"\n{material}\n\
             Material \"mix\" \"string materials\" [\"a\" \"m\"]\nShape \"sphere\"\n"
        )
    };
    let named = |params: &str| format!("MakeNamedMaterial \"m\" \"string type\" \"measured\" {params}");
    let c = converted(
        &scene(&named(&format!("\"string filename\" \"{}\"", good.display()))),
        Files::default(),
        false,
    )
    .unwrap();
    // The mix holds it: a measured material is no longer a reason to refuse one.
    let measured = |c: &convert::Converted| {
        c.desc
            .materials
            .iter()
            .find_map(|(_, m)| match m {
                crate::material::Material::Mix { materials, .. } => Some(materials[1].clone()),
                _ => None,
            })
            .unwrap()
    };
    let m = measured(&c);
    let crate::material::Material::Measured(b) = &m else {
        panic!("{m:?}")
    };
    // Named in the Debug form that scene fingerprints hash: by its file's
    // name and a hash of its bytes, not its folder.
    let shown = format!("{b:?}");
    assert!(shown.contains("\"good.bsdf\"") && shown.contains("hash: "), "{shown}");
    assert!(!shown.contains(&dir.path().display().to_string()), "{shown}");
    // The same file named again is read once: the same data.
    let c2 = converted(
        &scene(&named(&format!("\"string filename\" \"{}\"", good.display()))),
        Files::default(),
        false,
    )
    .unwrap();
    assert_eq!(measured(&c2), m);
    // A missing file, one that is not a tensor file, and no file at all:
    // each an error at its line, lenient or not.
    for lenient in [false, true] {
        let e = converted(
            &scene(&named("\"string filename\" \"nope.bsdf\"")),
            Files::default(),
            lenient,
        )
        .unwrap_err();
        assert!(
            e.starts_with("scene/main.pbrt:3:") && e.contains("measured: file \"nope.bsdf\" not found"),
            "{e}"
        );
        let e = converted(
            &scene(&named(&format!("\"string filename\" \"{}\"", bad.display()))),
            Files::default(),
            lenient,
        )
        .unwrap_err();
        assert!(
            e.starts_with("scene/main.pbrt:3:") && e.contains("bad.bsdf: not a tensor file"),
            "{e}"
        );
        let e = converted(&scene(&named("")), Files::default(), lenient).unwrap_err();
        assert!(e.starts_with("scene/main.pbrt:3: measured: no \"filename\""), "{e}");
        assert!(!e.contains('\n'));
    }
}

/// The scene's ray (ours mirrors pbrt's x) from (x, y, 0) along +z.
fn hit_at(scene: &crate::Scene, x: f32, y: f32) -> Option<crate::scene::Hit> {
    scene.intersect(
        &crate::math::Ray::new(Vec3::new(x, y, 0.0), Vec3::Z),
        0.0,
        f32::INFINITY,
    )
}

#[test]
fn partial_and_stretched_spheres_and_disks_are_where_pbrt_puts_them() {
    let one = |shape: &str| {
        let c = converted(
            &format!("WorldBegin\nTranslate 0 0 5\n{shape}\n"),
            Files::default(),
            false,
        )
        .unwrap();
        assert!(c.mirrored);
        crate::Scene::build(c.desc).unwrap()
    };
    // The far half only (object z >= 0): the ray meets it from inside,
    // where v = 1 (pbrt-v4's theta_zmax), its normal pbrt's outward one.
    let s = one("Shape \"sphere\" \"float zmin\" 0");
    let h = hit_at(&s, 0.0, 0.0).unwrap();
    assert!((h.t - 6.0).abs() < 1e-4 && (h.uv.y - 1.0).abs() < 1e-6, "{h:?}");
    assert!(h.ng.z > 0.999 && h.ns.z > 0.999, "{h:?}");
    let h = hit_at(&s, 0.6, 0.0).unwrap();
    assert!((h.t - 5.8).abs() < 2e-3, "{h:?}");
    // A wedge of phi in [0, 90] degrees: pbrt's (0.5, 0.5), ours (-0.5, 0.5).
    let s = one("Shape \"sphere\" \"float phimax\" 90");
    let h = hit_at(&s, -0.5, 0.5).unwrap();
    assert!((h.t - (5.0 - 0.5f32.sqrt())).abs() < 2e-3, "{h:?}");
    assert!((h.uv.x - 0.5).abs() < 1e-2, "{h:?}");
    assert!(hit_at(&s, 0.5, 0.5).is_none() && hit_at(&s, -0.5, -0.5).is_none());
    // An ellipsoid twice as wide along x as the sphere.
    let s = one("Scale 2 1 1\nShape \"sphere\"");
    let h = hit_at(&s, -1.5, 0.0).unwrap();
    assert!((h.t - (5.0 - 0.4375f32.sqrt())).abs() < 2e-3, "{h:?}");
    let n = Vec3::new(-1.5 / 4.0, 0.0, -0.4375f32.sqrt()).normalize();
    assert!(h.ns.dot(n) > 0.9999, "{h:?} {n}");
    assert!(hit_at(&s, 1.95, 0.0).is_some() && hit_at(&s, 2.05, 0.0).is_none());
    assert!(hit_at(&s, 0.0, 0.95).is_some() && hit_at(&s, 0.0, 1.05).is_none());
    // A quarter disk, and an annulus squeezed into an ellipse's ring.
    let s = one("Shape \"disk\" \"float phimax\" 90");
    let h = hit_at(&s, -0.5, 0.5).unwrap();
    assert!((h.t - 5.0).abs() < 1e-5, "{h:?}");
    assert!((h.uv - Vec2::new(0.5, 1.0 - 0.5f32.sqrt())).length() < 2e-3, "{h:?}");
    assert!(hit_at(&s, 0.5, 0.5).is_none() && hit_at(&s, -0.5, -0.5).is_none());
    let s = one("Scale 1 0.5 1\nShape \"disk\" \"float innerradius\" 0.5");
    assert!(hit_at(&s, 0.0, 0.2).is_none() && hit_at(&s, 0.0, 0.3).is_some() && hit_at(&s, 0.0, 0.55).is_none());
    assert!(hit_at(&s, 0.4, 0.0).is_none() && hit_at(&s, 0.6, 0.0).is_some());
    // Cuts that leave nothing are the file's error (pbrt-v4 draws nothing).
    for (shape, what) in [
        (
            "sphere\" \"float zmin\" 1.5",
            "sphere: zmin 1.5 and zmax 1 must leave a band",
        ),
        ("sphere\" \"float phimax\" 0", "sphere: phimax 0 must be > 0"),
        ("disk\" \"float phimax\" -5", "disk: phimax -5 must be > 0"),
    ] {
        let e = converted(&format!("WorldBegin\nShape \"{shape}\n"), Files::default(), false).unwrap_err();
        assert!(e.starts_with("scene/main.pbrt:2:1: ") && e.contains(what), "{e}");
    }
}

#[test]
fn meshed_quadrics_face_as_pbrts_normals() {
    // pbrt-v4 turns a quadric's normal inwards (a disk's to -z) under
    // ReverseOrientation or a transformation that swaps handedness, not
    // both: one-sided light leaves on that side, and a dielectric's inside
    // is behind it.
    for (attrs, inward) in [
        ("", false),
        ("ReverseOrientation\n", true),
        ("Scale -1 1 1\n", true),
        ("Scale -1 1 1\nReverseOrientation\n", false),
    ] {
        for shape in [
            "Shape \"sphere\" \"float zmin\" 0.2",
            "Shape \"sphere\" \"float phimax\" 300",
            "Shape \"disk\" \"float phimax\" 300",
            "Shape \"cylinder\" \"float phimax\" 300",
        ] {
            let text = format!(
                "WorldBegin\nTranslate 0 0 5\nAttributeBegin\n{attrs}AreaLightSource \"diffuse\"\n{shape}\nAttributeEnd\n\
                 {attrs}Material \"dielectric\"\n{shape}\n"
            );
            let c = converted(&text, Files::default(), false).unwrap();
            let outward = |v: [Vec3; 3]| {
                let centroid = (v[0] + v[1] + v[2]) / 3.0;
                let out = match &shape[7..11] {
                    "disk" => Vec3::Z,
                    "cyli" => centroid * Vec3::new(1.0, 1.0, 0.0),
                    _ => centroid - Vec3::new(0.0, 0.0, 5.0),
                };
                (v[1] - v[0]).cross(v[2] - v[0]).dot(out) > 0.0
            };
            let lights: Vec<_> = c
                .desc
                .lights
                .iter()
                .filter_map(|l| match l {
                    crate::light::Light::Triangle {
                        vertices, two_sided, ..
                    } => Some((*vertices, *two_sided)),
                    _ => None,
                })
                .collect();
            assert!(lights.len() > 100, "{attrs}{shape}");
            assert!(
                lights.iter().all(|&(v, two)| !two && outward(v) != inward),
                "{attrs}{shape}"
            );
            let tris = &c.desc.triangles;
            assert!(tris.len() > 100, "{attrs}{shape}");
            assert!(tris.iter().all(|t| outward(t.vertices) != inward), "{attrs}{shape}");
        }
    }
}
