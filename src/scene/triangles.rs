//! The description's triangles, kept as indexed meshes.
//!
//! A mesh read from a file shares each vertex among about six triangles.
//! Copying its position, normal and texture coordinates into every
//! triangle (108 bytes a triangle) made the description the largest table
//! of a large scene; here a triangle is three indices, its material and
//! how it takes its normals and coordinates (20 bytes), and each vertex is
//! stored once. `get` gives back the very `TriangleDesc` that was added,
//! value for value, so nothing downstream can tell the difference.

use glam::{Vec2, Vec3};

use super::TriangleDesc;

/// A face's flag: it shades with its vertices' normals.
const SMOOTH: u32 = 1 << 31;
/// Its texture coordinates: none, its vertices', or a triple of its own
/// (an index into `Triangles::face_uvs` past these two).
const NO_UVS: u32 = 0;
const VERTEX_UVS: u32 = 1;
const FIRST_FACE_UVS: u32 = 2;

#[derive(Clone, Copy, Debug, PartialEq)]
struct Face {
    vertices: [u32; 3],
    material: u32,
    /// `SMOOTH`, and in the other bits where the coordinates come from.
    kind: u32,
}

/// A face's texture coordinates, as `Triangles::push_face` takes them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FaceUvs {
    None,
    /// Its vertices' own (`add_vertices` was given them).
    Vertices,
    /// A triple of its own, in the order of its vertices: pbrt-v4's default
    /// coordinates, turned with a triangle whose winding was turned.
    Own([Vec2; 3]),
}

/// Triangles of a scene description: vertices shared within meshes.
#[derive(Clone, Debug, Default)]
pub struct Triangles {
    positions: Vec<Vec3>,
    /// Empty until a face shades with vertex normals, then one a vertex
    /// (zero for vertices whose faces have none).
    normals: Vec<Vec3>,
    /// Likewise for texture coordinates.
    uvs: Vec<Vec2>,
    faces: Vec<Face>,
    /// The coordinate triples faces hold of their own: a handful of
    /// distinct ones (pbrt-v4's default and its turns), each kept once.
    face_uvs: Vec<[Vec2; 3]>,
}

/// Two lists are equal when they hold the same triangles, however their
/// vertices are shared.
impl PartialEq for Triangles {
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter())
    }
}

impl Triangles {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn len(&self) -> usize {
        self.faces.len()
    }

    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// Vertices stored (shared ones once).
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Bytes held, for `raytracer info` and the memory figures.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.positions.capacity() * size_of::<Vec3>()
            + self.normals.capacity() * size_of::<Vec3>()
            + self.uvs.capacity() * size_of::<Vec2>()
            + self.faces.capacity() * size_of::<Face>()
            + self.face_uvs.capacity() * size_of::<[Vec2; 3]>()
    }

    /// Room for `faces` more triangles (their vertices come with them).
    pub fn reserve(&mut self, faces: usize) {
        self.faces.reserve(faces);
    }

    /// Room for exactly `faces` more triangles.
    pub fn reserve_exact(&mut self, faces: usize) {
        self.faces.reserve_exact(faces);
    }

    pub fn clear(&mut self) {
        *self = Self::default();
    }

    /// Triangle `i`, as it was added.
    pub fn get(&self, i: usize) -> Option<TriangleDesc> {
        self.faces.get(i).map(|f| self.expand(f))
    }

    fn expand(&self, f: &Face) -> TriangleDesc {
        TriangleDesc {
            vertices: f.vertices.map(|v| self.positions[v as usize]),
            normals: self.face_normals(f),
            uvs: self.face_uvs(f),
            material: f.material,
        }
    }

    fn face_normals(&self, f: &Face) -> Option<[Vec3; 3]> {
        (f.kind & SMOOTH != 0).then(|| f.vertices.map(|v| self.normals[v as usize]))
    }

    fn face_uvs(&self, f: &Face) -> Option<[Vec2; 3]> {
        match f.kind & !SMOOTH {
            NO_UVS => None,
            VERTEX_UVS => Some(f.vertices.map(|v| self.uvs[v as usize])),
            k => Some(self.face_uvs[(k - FIRST_FACE_UVS) as usize]),
        }
    }

    /// Triangle `i`'s material.
    pub fn material(&self, i: usize) -> Option<u32> {
        self.faces.get(i).map(|f| f.material)
    }

    /// Triangle `i`'s corners.
    pub fn vertices(&self, i: usize) -> Option<[Vec3; 3]> {
        let f = self.faces.get(i)?;
        Some(f.vertices.map(|v| self.positions[v as usize]))
    }

    /// Triangle `i`'s vertex normals, when it shades with them.
    pub fn normals(&self, i: usize) -> Option<[Vec3; 3]> {
        self.face_normals(self.faces.get(i)?)
    }

    /// Triangle `i`'s texture coordinates, when it has any.
    pub fn uvs(&self, i: usize) -> Option<[Vec2; 3]> {
        self.face_uvs(self.faces.get(i)?)
    }

    pub fn iter(&self) -> impl ExactSizeIterator<Item = TriangleDesc> + '_ {
        self.faces.iter().map(|f| self.expand(f))
    }

    /// Triangles `range`, in order (those of it that exist).
    pub fn range(&self, range: std::ops::Range<usize>) -> impl Iterator<Item = TriangleDesc> + '_ {
        self.faces.get(range).unwrap_or_default().iter().map(|f| self.expand(f))
    }

    /// Adds one triangle with vertices of its own.
    pub fn push(&mut self, t: TriangleDesc) {
        let base = self.add_vertices(
            &t.vertices,
            t.normals.as_ref().map(|n| &n[..]),
            t.uvs.as_ref().map(|u| &u[..]),
        );
        let uvs = match t.uvs {
            Some(_) => FaceUvs::Vertices,
            None => FaceUvs::None,
        };
        self.push_face(base, [0, 1, 2], t.normals.is_some(), uvs, t.material);
    }

    /// Adds a mesh's vertices, to be shared by the faces `push_face` adds
    /// with the returned base. Missing normals or coordinates are stored
    /// as zero once any face has some.
    pub fn add_vertices(&mut self, positions: &[Vec3], normals: Option<&[Vec3]>, uvs: Option<&[Vec2]>) -> u32 {
        let base = self.positions.len();
        self.positions.extend_from_slice(positions);
        let n = positions.len();
        fn fill<T: Copy>(table: &mut Vec<T>, given: Option<&[T]>, zero: T, base: usize, n: usize) {
            match given {
                Some(values) => {
                    table.resize(base, zero);
                    table.extend(values.iter().copied().chain(std::iter::repeat(zero)).take(n));
                }
                // A table still empty stays so until it is needed.
                None if table.is_empty() => {}
                None => table.resize(base + n, zero),
            }
        }
        fill(&mut self.normals, normals, Vec3::ZERO, base, n);
        fill(&mut self.uvs, uvs, Vec2::ZERO, base, n);
        // Four billion vertices would take 48 GB of positions alone, more
        // than any machine this runs on; the base saturates rather than wraps.
        u32::try_from(base).unwrap_or(u32::MAX)
    }

    /// Adds a face of vertices `base + vertices[k]` (from `add_vertices`):
    /// `smooth` when it shades with their normals.
    pub fn push_face(&mut self, base: u32, vertices: [u32; 3], smooth: bool, uvs: FaceUvs, material: u32) {
        let vertices = vertices.map(|v| base.saturating_add(v));
        let needed = vertices.iter().max().map_or(0, |&v| v as usize + 1);
        // The tables reach every vertex a face reads, even one added
        // before any had normals or coordinates.
        if smooth && self.normals.len() < needed {
            self.normals.resize(self.positions.len().max(needed), Vec3::ZERO);
        }
        if uvs == FaceUvs::Vertices && self.uvs.len() < needed {
            self.uvs.resize(self.positions.len().max(needed), Vec2::ZERO);
        }
        let uv_kind = match uvs {
            FaceUvs::None => NO_UVS,
            FaceUvs::Vertices => VERTEX_UVS,
            FaceUvs::Own(triple) => FIRST_FACE_UVS + self.face_uv_index(triple),
        };
        self.faces.push(Face {
            vertices,
            material,
            kind: uv_kind | if smooth { SMOOTH } else { 0 },
        });
    }

    fn face_uv_index(&mut self, triple: [Vec2; 3]) -> u32 {
        let bits = |t: &[Vec2; 3]| t.map(|v| [v.x.to_bits(), v.y.to_bits()]);
        // Faces' own triples are few; past a handful a new one is simply
        // kept (what a caller giving each face its own costs).
        let recent = self.face_uvs.len().saturating_sub(16);
        match self.face_uvs[recent..].iter().position(|t| bits(t) == bits(&triple)) {
            Some(k) => (recent + k) as u32,
            None => {
                self.face_uvs.push(triple);
                (self.face_uvs.len() - 1) as u32
            }
        }
    }

    /// Replaces triangle `i` by `t` (with vertices of its own).
    pub fn set(&mut self, i: usize, t: TriangleDesc) {
        if i >= self.len() {
            return;
        }
        self.push(t);
        if let Some(last) = self.faces.pop() {
            self.faces[i] = last;
        }
    }

    /// Maps every position by `point` and every normal by `vector`, and
    /// turns every face's winding (its coordinates, pbrt-v4's default
    /// ones too, turned with it): a reflection.
    pub fn reflect(&mut self, point: impl Fn(Vec3) -> Vec3, vector: impl Fn(Vec3) -> Vec3, default_uvs: [Vec2; 3]) {
        for p in &mut self.positions {
            *p = point(*p);
        }
        for n in &mut self.normals {
            *n = vector(*n);
        }
        let mut faces = std::mem::take(&mut self.faces);
        for f in &mut faces {
            let [a, b, c] = f.vertices;
            f.vertices = [a, c, b];
            let smooth = f.kind & SMOOTH;
            let own = match f.kind & !SMOOTH {
                VERTEX_UVS => continue,
                NO_UVS => default_uvs,
                k => self.face_uvs[(k - FIRST_FACE_UVS) as usize],
            };
            let [a, b, c] = own;
            f.kind = smooth | (FIRST_FACE_UVS + self.face_uv_index([a, c, b]));
        }
        self.faces = faces;
    }
}

/// The vertex normals and texture coordinates that hits read, for
/// triangles in an order of their own (the BVH's): each triangle its
/// corners into the description's shared tables (`Triangles`), 16 bytes
/// where a copy of its normals and coordinates took 68. Triangles that are
/// not in the description (the lights') keep theirs here.
#[derive(Clone, Debug, Default)]
pub struct ShadingTable {
    /// Per triangle; empty when none has usable normals or coordinates.
    corners: Vec<Corners>,
    /// The lights' vertex normals and coordinates, three a triangle.
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
}

#[derive(Clone, Copy, Debug)]
struct Corners {
    vertices: [u32; 3],
    /// `SMOOTH`, `OWN` and the coordinates' code, as a `Face`'s.
    kind: u32,
}

/// A `ShadingTable` face's flag: its corners are the table's own.
const OWN: u32 = 1 << 30;

/// Where a `ShadingTable`'s triangle comes from.
pub enum ShadingSource {
    /// The description's triangle `i`.
    Listed(usize),
    /// Normals and coordinates of its own, `own[k]` of `ShadingTable::gather`.
    Own(usize),
}

impl ShadingTable {
    /// The table of `n` triangles, triangle `k` from `source(k)`. Normals
    /// that fail `normals_ok` are not used (flat shading), nor coordinates
    /// that fail `uvs_ok` (the default ones); `own` holds triangles of
    /// their own, already checked.
    #[allow(clippy::type_complexity)]
    pub fn gather(
        list: &Triangles,
        n: usize,
        source: impl Fn(usize) -> ShadingSource + Sync + Send,
        own: &[(Option<[Vec3; 3]>, Option<[Vec2; 3]>)],
        normals_ok: impl Fn([Vec3; 3]) -> bool + Sync + Send,
        uvs_ok: impl Fn([Vec2; 3]) -> bool + Sync + Send,
    ) -> ShadingTable {
        use rayon::prelude::*;
        let mut table = ShadingTable::default();
        for (k, (normals, uvs)) in own.iter().enumerate() {
            debug_assert_eq!(table.normals.len(), 3 * k);
            table.normals.extend(normals.unwrap_or([Vec3::ZERO; 3]));
            table.uvs.extend(uvs.unwrap_or([Vec2::ZERO; 3]));
        }
        let corners: Vec<Corners> = (0..n)
            .into_par_iter()
            .map(|k| match source(k) {
                ShadingSource::Listed(i) => match list.faces.get(i) {
                    Some(f) => {
                        let smooth = list.face_normals(f).is_some_and(&normals_ok);
                        let uvs = match list.face_uvs(f) {
                            Some(uv) if uvs_ok(uv) => f.kind & !SMOOTH,
                            _ => NO_UVS,
                        };
                        Corners {
                            vertices: f.vertices,
                            kind: uvs | if smooth { SMOOTH } else { 0 },
                        }
                    }
                    None => Corners {
                        vertices: [0; 3],
                        kind: NO_UVS,
                    },
                },
                ShadingSource::Own(j) => {
                    let (normals, uvs) = own.get(j).copied().unwrap_or((None, None));
                    let base = 3 * j as u32;
                    Corners {
                        vertices: [base, base + 1, base + 2],
                        kind: OWN
                            | if normals.is_some() { SMOOTH } else { 0 }
                            | if uvs.is_some() { VERTEX_UVS } else { NO_UVS },
                    }
                }
            })
            .collect();
        // A table no hit would read anything from is left empty.
        if corners.par_iter().any(|c| c.kind & !OWN != 0) {
            table.corners = corners;
        }
        table
    }

    /// Bytes held.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.corners.capacity() * size_of::<Corners>()
            + self.normals.capacity() * size_of::<Vec3>()
            + self.uvs.capacity() * size_of::<Vec2>()
    }

    /// Triangle `k`'s vertex normals, when it shades with them.
    #[inline]
    pub fn normals(&self, list: &Triangles, k: usize) -> Option<[Vec3; 3]> {
        let c = self.corners.get(k)?;
        if c.kind & SMOOTH == 0 {
            return None;
        }
        let table = if c.kind & OWN != 0 {
            &self.normals
        } else {
            &list.normals
        };
        Some(gather(table, c.vertices))
    }

    /// Triangle `k`'s texture coordinates, when it has any.
    #[inline]
    pub fn uvs(&self, list: &Triangles, k: usize) -> Option<[Vec2; 3]> {
        let c = self.corners.get(k)?;
        match c.kind & !(SMOOTH | OWN) {
            NO_UVS => None,
            VERTEX_UVS => {
                let table = if c.kind & OWN != 0 { &self.uvs } else { &list.uvs };
                Some(gather(table, c.vertices))
            }
            code => list.face_uvs.get((code - FIRST_FACE_UVS) as usize).copied(),
        }
    }
}

/// A triangle's three entries of a vertex table, written out: `[_; 3]::map`
/// with its bounds checks stayed a call of its own on every hit.
#[inline(always)]
fn gather<T: Copy>(table: &[T], [a, b, c]: [u32; 3]) -> [T; 3] {
    [table[a as usize], table[b as usize], table[c as usize]]
}

impl Extend<TriangleDesc> for Triangles {
    fn extend<I: IntoIterator<Item = TriangleDesc>>(&mut self, iter: I) {
        for t in iter {
            self.push(t);
        }
    }
}

impl FromIterator<TriangleDesc> for Triangles {
    fn from_iter<I: IntoIterator<Item = TriangleDesc>>(iter: I) -> Self {
        let mut t = Triangles::new();
        t.extend(iter);
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(k: f32, normals: bool, uvs: bool) -> TriangleDesc {
        TriangleDesc {
            vertices: [Vec3::new(k, 0.0, 1.0), Vec3::new(0.0, k, 2.0), Vec3::new(3.0, 0.5, k)],
            normals: normals.then_some([Vec3::X, Vec3::Y * k, Vec3::Z]),
            uvs: uvs.then_some([Vec2::new(k, 0.25), Vec2::ONE, Vec2::new(0.5, k)]),
            material: k as u32,
        }
    }

    #[test]
    fn triangles_come_back_as_they_were_added_whatever_their_neighbours_hold() {
        let mut list = Triangles::new();
        let mut expected = vec![];
        for k in 0..24 {
            let t = tri(k as f32, k % 3 == 1, k % 4 >= 2);
            expected.push(t.clone());
            list.push(t);
        }
        assert_eq!(list.len(), 24);
        for (i, t) in expected.iter().enumerate() {
            assert_eq!(list.get(i).as_ref(), Some(t), "triangle {i}");
            assert_eq!(list.material(i), Some(t.material));
            assert_eq!(list.vertices(i), Some(t.vertices));
            assert_eq!(list.normals(i), t.normals);
            assert_eq!(list.uvs(i), t.uvs);
        }
        assert_eq!(list.get(24), None);
        assert!(list.iter().eq(expected.iter().cloned()));
        assert!(list.range(3..7).eq(expected[3..7].iter().cloned()));
    }

    #[test]
    fn a_mesh_shares_its_vertices_and_its_faces_read_them_in_their_own_order() {
        let mut list = Triangles::new();
        list.push(tri(9.0, false, false));
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE];
        let n = [Vec3::Z, Vec3::Z, -Vec3::Z, Vec3::X];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE];
        let base = list.add_vertices(&p, Some(&n), Some(&uv));
        assert_eq!(base, 3);
        list.push_face(base, [0, 1, 2], true, FaceUvs::Vertices, 4);
        list.push_face(base, [3, 2, 1], false, FaceUvs::Own([Vec2::ONE; 3]), 5);
        list.push_face(base, [1, 3, 0], true, FaceUvs::None, 6);
        assert_eq!(list.vertex_count(), 7);
        let t = list.get(2).unwrap();
        assert_eq!(t.vertices, [p[3], p[2], p[1]]);
        assert_eq!((t.normals, t.uvs, t.material), (None, Some([Vec2::ONE; 3]), 5));
        let t = list.get(3).unwrap();
        assert_eq!((t.normals, t.uvs), (Some([n[1], n[3], n[0]]), None));
        assert_eq!(list.get(1).unwrap().uvs, Some([uv[0], uv[1], uv[2]]));
        // The first triangle, added before any normals, still has none.
        assert_eq!(list.get(0), Some(tri(9.0, false, false)));
        // A later face with normals on vertices added without them reads zeros.
        let base = list.add_vertices(&p[..3], None, None);
        list.push_face(base, [0, 1, 2], true, FaceUvs::Vertices, 0);
        assert_eq!(list.get(4).unwrap().normals, Some([Vec3::ZERO; 3]));
        assert_eq!(list.get(4).unwrap().uvs, Some([Vec2::ZERO; 3]));
        assert_eq!(list.get(1).unwrap().uvs, Some([uv[0], uv[1], uv[2]]));
    }

    #[test]
    fn a_reflection_turns_every_face_as_turning_each_triangle_would() {
        let default_uvs = [Vec2::ZERO, Vec2::X, Vec2::ONE];
        let point = |p: Vec3| Vec3::new(-p.x, p.y, p.z) + Vec3::Y;
        let vector = |v: Vec3| Vec3::new(-v.x, v.y, v.z);
        let mut list = Triangles::new();
        let base = list.add_vertices(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z], Some(&[Vec3::Z; 4]), None);
        list.push_face(base, [0, 1, 2], true, FaceUvs::None, 0);
        list.push_face(base, [1, 2, 3], false, FaceUvs::Own([Vec2::Y, Vec2::X, Vec2::ZERO]), 1);
        for k in 0..6 {
            list.push(tri(k as f32, k % 2 == 0, k % 3 == 0));
        }
        let before: Vec<_> = list.iter().collect();
        list.reflect(point, vector, default_uvs);
        for (t, r) in before.iter().zip(list.iter()) {
            let turn = |[a, b, c]: [Vec3; 3]| [a, c, b];
            assert_eq!(r.vertices, turn(t.vertices.map(point)));
            assert_eq!(r.normals, t.normals.map(|n| turn(n.map(vector))));
            let [a, b, c] = t.uvs.unwrap_or(default_uvs);
            assert_eq!(r.uvs, Some([a, c, b]));
            assert_eq!(r.material, t.material);
        }
    }

    #[test]
    fn replacing_a_triangle_leaves_the_others_and_equality_ignores_sharing() {
        let mut list: Triangles = (0..4).map(|k| tri(k as f32, true, true)).collect();
        list.set(2, tri(7.0, false, true));
        list.set(9, tri(8.0, false, false));
        let expected = [
            tri(0.0, true, true),
            tri(1.0, true, true),
            tri(7.0, false, true),
            tri(3.0, true, true),
        ];
        assert!(list.iter().eq(expected.iter().cloned()));
        let mut shared = Triangles::new();
        let t = tri(1.0, true, true);
        let base = shared.add_vertices(
            &t.vertices,
            t.normals.as_ref().map(|n| &n[..]),
            t.uvs.as_ref().map(|u| &u[..]),
        );
        shared.push_face(base, [0, 1, 2], true, FaceUvs::Vertices, 1);
        shared.push_face(base, [0, 1, 2], true, FaceUvs::Vertices, 1);
        let copies: Triangles = [t.clone(), t].into_iter().collect();
        assert_eq!(shared, copies);
        assert_ne!(shared, list);
    }

    #[test]
    fn the_shading_table_reads_each_triangle_in_its_own_order_and_drops_what_fails_its_checks() {
        let mut list = Triangles::new();
        let mut added = vec![];
        for k in 0..12 {
            let mut t = tri(k as f32, k % 2 == 0, k % 3 != 0);
            if k == 4 {
                // Normals that the check refuses: the triangle shades flat.
                t.normals = Some([Vec3::ZERO, Vec3::X, Vec3::Y]);
            }
            if k == 5 {
                t.uvs = Some([Vec2::NAN, Vec2::ZERO, Vec2::ONE]);
            }
            added.push(t.clone());
            list.push(t);
        }
        let base = list.add_vertices(&[Vec3::ZERO, Vec3::X, Vec3::Y], None, None);
        list.push_face(base, [0, 1, 2], false, FaceUvs::Own([Vec2::Y, Vec2::X, Vec2::ONE]), 3);
        added.push(list.get(12).unwrap());
        let own = [
            (Some([Vec3::Z, Vec3::Y, Vec3::X]), None),
            (None, Some([Vec2::ONE, Vec2::X, Vec2::Y])),
        ];
        // Listed triangles backwards, the two of their own between.
        let order: Vec<ShadingSource> = (0..13)
            .rev()
            .map(ShadingSource::Listed)
            .chain([ShadingSource::Own(1), ShadingSource::Own(0)])
            .collect();
        let pick = |k: usize| match order[k] {
            ShadingSource::Listed(i) => ShadingSource::Listed(i),
            ShadingSource::Own(j) => ShadingSource::Own(j),
        };
        let normals_ok = |ns: [Vec3; 3]| ns.iter().all(|n| n.length_squared() > 0.0);
        let uvs_ok = |uv: [Vec2; 3]| uv.iter().all(|c| c.is_finite());
        let table = ShadingTable::gather(&list, order.len(), pick, &own, normals_ok, uvs_ok);
        for (k, source) in order.iter().enumerate() {
            let (normals, uvs) = match *source {
                ShadingSource::Listed(i) => (
                    added[i].normals.filter(|&n| normals_ok(n)),
                    added[i].uvs.filter(|&u| uvs_ok(u)),
                ),
                ShadingSource::Own(j) => own[j],
            };
            assert_eq!(table.normals(&list, k), normals, "slot {k}");
            assert_eq!(table.uvs(&list, k), uvs, "slot {k}");
        }
        assert_eq!(table.normals(&list, 1), None, "triangle 11: no normals");
        assert_eq!(table.normals(&list, 8), None, "triangle 4: refused");
        assert_eq!(table.uvs(&list, 7), None, "triangle 5: refused");
        assert_eq!(table.uvs(&list, 14), None, "its own, without coordinates");
        assert_eq!((table.normals(&list, 15), table.uvs(&list, 15)), (None, None));
        assert_eq!(table.uvs(&list, 0), Some([Vec2::Y, Vec2::X, Vec2::ONE]), "a face's own");
        // Nothing to read: an empty table.
        let flat: Triangles = (0..3).map(|k| tri(k as f32, false, false)).collect();
        let table = ShadingTable::gather(&flat, 3, ShadingSource::Listed, &[], normals_ok, uvs_ok);
        assert_eq!(table.heap_bytes(), 0);
    }

    #[test]
    fn a_mesh_costs_twenty_bytes_a_triangle_and_its_vertices_once() {
        // A grid of n x n quads: (n + 1)^2 vertices, 2 n^2 triangles.
        let n = 100u32;
        let side = n + 1;
        let positions: Vec<Vec3> = (0..side * side)
            .map(|k| Vec3::new((k % side) as f32, (k / side) as f32, 0.0))
            .collect();
        let normals = vec![Vec3::Z; positions.len()];
        let uvs: Vec<Vec2> = positions.iter().map(|p| p.truncate() / n as f32).collect();
        let mut list = Triangles::new();
        list.reserve_exact(2 * (n * n) as usize);
        let base = list.add_vertices(&positions, Some(&normals), Some(&uvs));
        for y in 0..n {
            for x in 0..n {
                let k = y * side + x;
                list.push_face(base, [k, k + 1, k + side + 1], true, FaceUvs::Vertices, 0);
                list.push_face(base, [k, k + side + 1, k + side], true, FaceUvs::Vertices, 0);
            }
        }
        let (faces, vertices) = (list.len(), list.vertex_count());
        assert_eq!((faces, vertices), (20_000, 10_201));
        // Positions, normals and coordinates: 32 bytes a vertex, allowing
        // for the vectors' growth; 20 bytes a triangle.
        let bytes = list.heap_bytes();
        assert!(bytes <= 20 * faces + 2 * 32 * vertices, "{bytes} bytes");
        assert!(
            bytes < 40 * faces,
            "{bytes} bytes: a copy a triangle would take 108 each"
        );
        let table = ShadingTable::gather(&list, faces, ShadingSource::Listed, &[], |_| true, |_| true);
        assert_eq!(table.heap_bytes(), 16 * faces);
        assert_eq!(table.normals(&list, 7), Some([Vec3::Z; 3]));
    }
}
