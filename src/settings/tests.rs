use super::*;

fn layer(values: &[(&str, Value)], origin: Origin) -> Layer {
    let mut l = Layer::default();
    for (name, v) in values {
        l.set(name, *v, origin.clone()).unwrap();
    }
    l
}

fn file(line: usize) -> Origin {
    Origin::SceneFile {
        path: "scenes/x.toml".into(),
        line,
    }
}

fn resolve3(cli: &Layer, scene: &Layer, preset: &Layer) -> Result<RenderSettings, SettingError> {
    resolve(
        Layers {
            command_line: cli,
            scene_file: scene,
            preset,
        },
        StateFiles::default(),
    )
}

#[test]
fn the_defaults_are_the_tables() {
    let d = RenderSettings::default();
    assert_eq!((d.ssaa, d.shadow_samples, d.spp, d.passes), (4, 4, 64, 64));
    assert_eq!(
        (d.integrator, d.filter, d.seed, d.alpha),
        (IntegratorKind::Direct, Filter::Box, 0, 0.7)
    );
    let p = d.photon;
    assert_eq!((p.photons, p.max_bounces, p.caustic_photons), (200_000, 5, 100_000));
    assert_eq!((p.gather.radius, p.gather.k, p.caustic_radius), (0.1, None, 0.025));
    assert!(p.roulette && !p.store_first_hit && !p.precompute_irradiance && !p.gather.cone);
    assert_eq!(d.validate(), Ok(()));
    // Every table default is a valid value of its own kind.
    for s in SETTINGS {
        if let Some(v) = s.default.value() {
            assert_eq!(s.check(&v), Ok(()), "{}", s.name);
        }
    }
}

#[test]
fn the_command_line_wins_over_the_file_over_the_preset_over_the_default() {
    let preset = layer(
        &[
            ("photons", Value::Int(1)),
            ("ssaa", Value::Int(2)),
            ("spp", Value::Int(3)),
        ],
        Origin::Preset("p".into()),
    );
    let scene = layer(&[("photons", Value::Int(10)), ("ssaa", Value::Int(20))], file(3));
    let cli = layer(&[("photons", Value::Int(100))], Origin::CommandLine);
    let s = resolve3(&cli, &scene, &preset).unwrap();
    assert_eq!((s.photon.photons, s.ssaa, s.spp, s.shadow_samples), (100, 20, 3, 4));
}

#[test]
fn derived_defaults_follow_the_settings_they_depend_on() {
    let none = Layer::default();
    let sppm = layer(&[("integrator", Value::Name("sppm"))], Origin::CommandLine);
    assert_eq!(resolve3(&sppm, &none, &none).unwrap().photon.max_bounces, 100);
    // A k typed by the user is not bounded by the scene's radius...
    let k = layer(&[("gather_k", Value::Int(50))], Origin::CommandLine);
    let radius = layer(&[("gather_radius", Value::Real(0.06))], file(4));
    let s = resolve3(&k, &radius, &none).unwrap();
    assert_eq!((s.photon.gather.k, s.photon.gather.radius), (Some(50), f32::INFINITY));
    // ...but one given beside it is.
    let both = layer(
        &[("gather_k", Value::Int(50)), ("gather_radius", Value::Real(0.2))],
        file(4),
    );
    let s = resolve3(&none, &both, &none).unwrap();
    assert_eq!((s.photon.gather.k, s.photon.gather.radius), (Some(50), 0.2));
}

#[test]
fn errors_say_where_the_value_came_from() {
    let mut l = Layer::default();
    let e = l.set("max_bounces", Value::Int(200), file(12)).unwrap_err();
    assert_eq!(
        e.to_string(),
        "scenes/x.toml:12: max_bounces = 200: must be between 1 and 100"
    );
    let e = l.set_text("max_bounces", "200", Origin::CommandLine).unwrap_err();
    assert_eq!(e.to_string(), "--max-bounces 200: must be between 1 and 100");
    let e = l
        .set("ssaa", Value::Int(0), Origin::Preset("cornell-final".into()))
        .unwrap_err();
    assert_eq!(
        e.to_string(),
        "preset cornell-final: ssaa = 0: must be between 1 and 64"
    );
    let e = l.set_text("alpha", "nan", Origin::CommandLine).unwrap_err();
    assert!(e.to_string().starts_with("--alpha nan: must be a number > 0"), "{e}");
    let e = l.set_text("integrator", "mlt", Origin::CommandLine).unwrap_err();
    assert_eq!(
        e.to_string(),
        "--integrator mlt: expected one of direct, photon, path, sppm, bdpt"
    );
    assert_eq!(e.setting, "integrator");
    assert_eq!(e.origin, Origin::CommandLine);
}

#[test]
fn sppm_refuses_gather_k_from_any_source() {
    let none = Layer::default();
    let sppm = layer(&[("integrator", Value::Name("sppm"))], Origin::CommandLine);
    let k = layer(&[("gather_k", Value::Int(8))], file(7));
    let e = resolve3(&sppm, &k, &none).unwrap_err();
    assert_eq!(e.origin, file(7));
    assert!(
        e.to_string()
            .starts_with("scenes/x.toml:7: gather_k = 8: not with integrator sppm"),
        "{e}"
    );
    // Settings made in code get the same answer.
    let mut s = RenderSettings {
        integrator: IntegratorKind::Sppm,
        ..Default::default()
    };
    s.photon.gather.k = Some(8);
    assert_eq!(s.validate().unwrap_err().origin, Origin::Caller);
}

#[test]
fn options_of_one_integrator_typed_for_another_are_refused() {
    let none = Layer::default();
    let passes = layer(&[("passes", Value::Int(3))], Origin::CommandLine);
    let e = resolve3(&passes, &none, &none).unwrap_err();
    assert_eq!(e.to_string(), "--passes 3: only for integrator sppm");
    // In a scene file they are recommendations for when SPPM is chosen.
    assert!(resolve3(&none, &passes, &none).is_ok());
}

#[test]
fn absurd_photon_counts_are_refused_before_any_work() {
    let none = Layer::default();
    let huge = layer(
        &[("integrator", Value::Name("photon")), ("photons", Value::Int(1 << 40))],
        Origin::CommandLine,
    );
    let e = resolve3(&huge, &none, &none).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("--photons 1099511627776: the photon map needs"),
        "{e}"
    );
}

#[test]
fn every_setting_parses_its_default_text_and_refuses_nonsense() {
    for s in SETTINGS {
        if let Some(v) = s.default.value() {
            assert_eq!(s.parse(&v.to_string()), Ok(v), "{}", s.name);
        }
        assert!(s.parse("nonsense").is_err(), "{}", s.name);
        assert_eq!(spec(s.name).map(|x| x.name), Some(s.name));
    }
    assert!(spec("no_such_setting").is_none());
}

#[test]
fn the_scene_format_document_lists_every_setting() {
    let doc = include_str!("../../docs/scene-format.md");
    assert!(
        doc.contains(&markdown_table()),
        "docs/scene-format.md does not hold the settings table; paste settings::markdown_table():\n{}",
        markdown_table()
    );
}
