//! Loop subdivision surfaces as pbrt-v4's `loopsubdiv` shape makes them: a
//! triangle control mesh is refined `levels` times with Loop's masks, every
//! vertex is then moved to its limit position, and each vertex gets the
//! normal of the limit surface there (Loop, "Smooth Subdivision Surfaces
//! Based on Triangles", 1987; Physically Based Rendering, 3rd ed., 3.8).
//!
//! The mesh is kept as half-edges in flat arrays: half-edge `3f + k` runs
//! from corner `k` of triangle `f` to corner `k + 1`, and its twin is the
//! neighbour's half-edge along the same edge, or `NONE` on the boundary. The
//! children's twins follow from the parents', so the edge map is built once,
//! for the control mesh.

use crate::math::Vec3;
use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::f32::consts::PI;

/// Most triangles a subdivision may produce (2^24, under 1 GiB at the
/// peak); each level multiplies the count by four.
pub const MAX_TRIANGLES: u64 = 1 << 24;

/// No twin: the half-edge lies on the boundary.
const NONE: u32 = u32::MAX;

/// The refined mesh on its limit surface.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SubdividedMesh {
    pub positions: Vec<Vec3>,
    /// Unit limit-surface normals, one per position, on the side the
    /// triangles' winding faces (`cross(p1 - p0, p2 - p0)`).
    pub normals: Vec<Vec3>,
    /// Wound like the control triangles they refine.
    pub triangles: Vec<[u32; 3]>,
}

#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SubdivisionError {
    #[error("loop subdivision needs at least one triangle")]
    NoTriangles,
    #[error("triangle {face} refers to vertex {index}, but there are only {vertices} vertices")]
    IndexOutOfRange { face: usize, index: u32, vertices: usize },
    #[error("triangle {face} uses a vertex more than once ({indices:?})")]
    DegenerateFace { face: usize, indices: [u32; 3] },
    #[error(
        "the edge between vertices {a} and {b} is shared by more than two triangles (the third is triangle {face})"
    )]
    NonManifoldEdge { a: u32, b: u32, face: usize },
    #[error(
        "triangles {first} and {second} both run from vertex {a} to vertex {b}: neighbouring triangles must be \
         wound the same way (the surface must be orientable)"
    )]
    InconsistentOrientation {
        a: u32,
        b: u32,
        first: usize,
        second: usize,
    },
    #[error("the triangles at vertex {vertex} do not form one fan around it (they meet only at the vertex)")]
    NonManifoldVertex { vertex: u32 },
    #[error(
        "{levels} levels of subdivision would turn {faces} triangles into {faces} x 4^{levels}, more than the \
         limit of {MAX_TRIANGLES} (2^24) triangles"
    )]
    TooManyLevels { levels: u32, faces: usize },
}

/// Loop subdivision (pbrt-v4's `loopsubdiv` shape): refines the control
/// triangles `levels` times, then places every vertex on the limit surface
/// and gives it the limit normal. Level 0 still moves the control vertices
/// to the limit surface, as pbrt does.
///
/// The control mesh must be a consistently wound 2-manifold, open or closed;
/// pbrt follows its adjacency pointers blindly and misbehaves otherwise.
/// Vertices no triangle uses are dropped (pbrt crashes on them); the others
/// come first in the output, in input order, followed by the vertices each
/// level adds.
///
/// pbrt's cross product of the limit tangents points against the winding
/// (inward on an outward-wound closed mesh), and its triangles turn their
/// geometric normal to that side, so a one-sided area light on a
/// `loopsubdiv` shape emits against the winding there. The normals returned
/// here follow the winding instead; negate them to reproduce pbrt's side.
pub fn loop_subdivide(
    levels: u32,
    positions: &[Vec3],
    indices: &[[u32; 3]],
) -> Result<SubdividedMesh, SubdivisionError> {
    check_size(levels, indices.len())?;
    let mut mesh = HalfEdgeMesh::new(positions, indices)?;
    for _ in 0..levels {
        mesh = mesh.refine();
    }
    Ok(mesh.limit_surface())
}

/// Refuses the work up front rather than running out of memory midway.
fn check_size(levels: u32, faces: usize) -> Result<(), SubdivisionError> {
    if faces == 0 {
        return Err(SubdivisionError::NoTriangles);
    }
    let too_many = SubdivisionError::TooManyLevels { levels, faces };
    let mut triangles = faces as u64;
    if triangles > MAX_TRIANGLES {
        return Err(too_many);
    }
    for _ in 0..levels {
        triangles *= 4;
        if triangles > MAX_TRIANGLES {
            return Err(too_many);
        }
    }
    Ok(())
}

/// Loop's weight for each one-ring neighbour of an interior vertex of
/// valence `n`, with Warren's simplification that pbrt uses; it equals
/// Loop's 1/16 at the regular valence 6.
fn beta(n: usize) -> f32 {
    if n == 3 {
        3.0 / 16.0
    } else {
        3.0 / (8.0 * n as f32)
    }
}

/// Neighbour weight of the limit mask, from the dominant left eigenvector
/// of the subdivision matrix for the `beta` above.
fn limit_gamma(n: usize) -> f32 {
    1.0 / (n as f32 + 3.0 / (8.0 * beta(n)))
}

struct HalfEdgeMesh {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    twins: Vec<u32>,
}

/// The half-edge before `h` in its triangle.
fn prev(h: usize) -> usize {
    if h.is_multiple_of(3) {
        h + 2
    } else {
        h - 1
    }
}

impl HalfEdgeMesh {
    /// Checks the control mesh and links it. Afterwards every index is in
    /// range and the mesh is a consistently wound manifold, which `refine`
    /// preserves, so the later stages need no checks.
    fn new(positions: &[Vec3], indices: &[[u32; 3]]) -> Result<Self, SubdivisionError> {
        // Check the triangles and mark the vertices they use
        let mut used = vec![false; positions.len()];
        for (face, tri) in indices.iter().enumerate() {
            for &index in tri {
                match used.get_mut(index as usize) {
                    Some(u) => *u = true,
                    None => {
                        return Err(SubdivisionError::IndexOutOfRange {
                            face,
                            index,
                            vertices: positions.len(),
                        })
                    }
                }
            }
            let [a, b, c] = *tri;
            if a == b || b == c || c == a {
                return Err(SubdivisionError::DegenerateFace { face, indices: *tri });
            }
        }

        // Number the used vertices in input order
        let mut remap = vec![NONE; positions.len()];
        let mut original = Vec::new();
        let mut kept = Vec::new();
        for (i, (&u, &p)) in used.iter().zip(positions).enumerate() {
            if u {
                remap[i] = original.len() as u32;
                original.push(i as u32);
                kept.push(p);
            }
        }
        let triangles: Vec<[u32; 3]> = indices.iter().map(|t| t.map(|i| remap[i as usize])).collect();
        let mut mesh = HalfEdgeMesh {
            positions: kept,
            triangles,
            twins: vec![NONE; 3 * indices.len()],
        };

        // Pair the half-edges of each edge; a third one makes it non-manifold
        let mut edges: HashMap<(u32, u32), [u32; 2]> = HashMap::with_capacity(3 * indices.len() / 2 + 1);
        for h in 0..mesh.twins.len() {
            let (a, b) = (mesh.tail(h), mesh.head(h));
            match edges.entry((a.min(b), a.max(b))) {
                Entry::Vacant(e) => {
                    e.insert([h as u32, NONE]);
                }
                Entry::Occupied(mut e) => {
                    let pair = e.get_mut();
                    if pair[1] != NONE {
                        return Err(SubdivisionError::NonManifoldEdge {
                            a: original[a as usize],
                            b: original[b as usize],
                            face: h / 3,
                        });
                    }
                    pair[1] = h as u32;
                }
            }
        }
        // In half-edge order rather than map order, so that the error is reproducible
        for h in 0..mesh.twins.len() {
            let (a, b) = (mesh.tail(h), mesh.head(h));
            let Some(&[first, second]) = edges.get(&(a.min(b), a.max(b))) else {
                continue;
            };
            if second == NONE {
                continue;
            }
            if mesh.tail(first as usize) == mesh.tail(second as usize) {
                return Err(SubdivisionError::InconsistentOrientation {
                    a: original[a as usize],
                    b: original[b as usize],
                    first: first as usize / 3,
                    second: second as usize / 3,
                });
            }
            mesh.twins[h] = if first as usize == h { second } else { first };
        }

        // A vertex whose ring walk misses some of its triangles is a pinch point
        let mut corners = vec![0usize; mesh.positions.len()];
        for tri in &mesh.triangles {
            for &v in tri {
                corners[v as usize] += 1;
            }
        }
        let starts = mesh.starts();
        let mut ring = Vec::new();
        for (v, &start) in starts.iter().enumerate() {
            let boundary = mesh.ring(start, &mut ring);
            let fan = if boundary { ring.len() - 1 } else { ring.len() };
            if fan != corners[v] {
                return Err(SubdivisionError::NonManifoldVertex { vertex: original[v] });
            }
        }
        Ok(mesh)
    }

    fn tail(&self, h: usize) -> u32 {
        self.triangles[h / 3][h % 3]
    }

    fn head(&self, h: usize) -> u32 {
        self.triangles[h / 3][(h + 1) % 3]
    }

    /// One outgoing half-edge per vertex to walk its ring from: on the
    /// boundary the one without a twin, so that the walk covers the whole fan.
    fn starts(&self) -> Vec<u32> {
        let mut starts = vec![NONE; self.positions.len()];
        for h in 0..self.twins.len() {
            let v = self.tail(h) as usize;
            if starts[v] == NONE || self.twins[h] == NONE {
                starts[v] = h as u32;
            }
        }
        starts
    }

    /// Fills `ring` with the neighbours of the tail of `start`, in the
    /// winding's (counter-clockwise) order, and says whether the vertex is on
    /// the boundary. A boundary ring runs from one boundary neighbour to the
    /// other, as pbrt's does; its length is the vertex's valence either way.
    fn ring(&self, start: u32, ring: &mut Vec<u32>) -> bool {
        ring.clear();
        let mut h = start as usize;
        // Bounded so that a broken mesh cannot hang the walk
        for _ in 0..self.twins.len() {
            ring.push(self.head(h));
            let into = prev(h);
            let twin = self.twins[into];
            if twin == NONE {
                ring.push(self.tail(into));
                return true;
            }
            if twin == start {
                return false;
            }
            h = twin as usize;
        }
        false
    }

    /// One level of Loop subdivision: each triangle becomes four, with the
    /// child at corner `j` keeping the parent's corner `j` and the centre
    /// child last, as pbrt orders them.
    fn refine(&self) -> HalfEdgeMesh {
        let nf = self.triangles.len();
        let p = &self.positions;
        let mut positions = Vec::with_capacity(p.len() + 3 * nf / 2 + 1);

        // Move the old (even) vertices; they keep their indices
        let starts = self.starts();
        let mut ring = Vec::new();
        for (v, &start) in starts.iter().enumerate() {
            let boundary = self.ring(start, &mut ring);
            positions.push(if boundary {
                boundary_mask(p, v, &ring, 1.0 / 8.0)
            } else {
                one_ring_mask(p, v, &ring, beta(ring.len()))
            });
        }

        // Add one (odd) vertex per edge, numbered in order of first use
        let mut edge_vertex = vec![NONE; 3 * nf];
        for h in 0..3 * nf {
            let twin = self.twins[h];
            if twin != NONE && (twin as usize) < h {
                continue;
            }
            let ends = p[self.tail(h) as usize] + p[self.head(h) as usize];
            positions.push(if twin == NONE {
                0.5 * ends
            } else {
                let across = p[self.tail(prev(h)) as usize] + p[self.tail(prev(twin as usize)) as usize];
                3.0 / 8.0 * ends + 1.0 / 8.0 * across
            });
            let id = (positions.len() - 1) as u32;
            edge_vertex[h] = id;
            if twin != NONE {
                edge_vertex[twin as usize] = id;
            }
        }

        // Split each triangle and link the children
        let mut triangles = Vec::with_capacity(4 * nf);
        let mut twins = vec![NONE; 12 * nf];
        // Half-edge `e` of child `c` of triangle `f`
        let child = |f: usize, c: usize, e: usize| 3 * (4 * f + c) + e;
        for (f, &[v0, v1, v2]) in self.triangles.iter().enumerate() {
            let [m0, m1, m2] = [edge_vertex[3 * f], edge_vertex[3 * f + 1], edge_vertex[3 * f + 2]];
            triangles.extend_from_slice(&[[v0, m0, m2], [m0, v1, m1], [m2, m1, v2], [m0, m1, m2]]);
            for j in 0..3 {
                let (jn, jp) = ((j + 1) % 3, (j + 2) % 3);
                // The centre child's edge j is shared with child j + 1
                twins[child(f, 3, j)] = child(f, jn, jp) as u32;
                twins[child(f, jn, jp)] = child(f, 3, j) as u32;
                // Parent edge j is halved: child j's edge j, then child j + 1's
                let twin = self.twins[3 * f + j];
                if twin != NONE {
                    let (g, k) = (twin as usize / 3, twin as usize % 3);
                    twins[child(f, j, j)] = child(g, (k + 1) % 3, k) as u32;
                    twins[child(f, jn, j)] = child(g, k, k) as u32;
                }
            }
        }
        HalfEdgeMesh {
            positions,
            triangles,
            twins,
        }
    }

    /// Moves every vertex to its limit position, then takes normals from the
    /// limit tangents evaluated on those limit positions, as pbrt does.
    fn limit_surface(self) -> SubdividedMesh {
        let starts = self.starts();
        let mut ring = Vec::new();
        let mut limit = Vec::with_capacity(self.positions.len());
        for (v, &start) in starts.iter().enumerate() {
            let boundary = self.ring(start, &mut ring);
            limit.push(if boundary {
                boundary_mask(&self.positions, v, &ring, 1.0 / 5.0)
            } else {
                one_ring_mask(&self.positions, v, &ring, limit_gamma(ring.len()))
            });
        }
        let mut normals = Vec::with_capacity(limit.len());
        for (v, &start) in starts.iter().enumerate() {
            let boundary = self.ring(start, &mut ring);
            normals.push(limit_normal(&limit, v, &ring, boundary));
        }
        SubdividedMesh {
            positions: limit,
            normals,
            triangles: self.triangles,
        }
    }
}

/// `weight` on each one-ring neighbour, the rest on the vertex itself.
fn one_ring_mask(p: &[Vec3], v: usize, ring: &[u32], weight: f32) -> Vec3 {
    let sum: Vec3 = ring.iter().map(|&r| p[r as usize]).sum();
    (1.0 - ring.len() as f32 * weight) * p[v] + weight * sum
}

/// `weight` on each of the two boundary neighbours: boundary vertices follow
/// the cubic B-spline of the boundary polygon and ignore the interior.
fn boundary_mask(p: &[Vec3], v: usize, ring: &[u32], weight: f32) -> Vec3 {
    let (first, last) = (ring[0] as usize, ring[ring.len() - 1] as usize);
    (1.0 - 2.0 * weight) * p[v] + weight * (p[first] + p[last])
}

/// The limit normal from pbrt's tangent masks, taken over offsets from the
/// vertex (the masks sum to zero, so this is pbrt's value with less
/// cancellation far from the origin).
fn limit_normal(p: &[Vec3], v: usize, ring: &[u32], boundary: bool) -> Vec3 {
    let n = ring.len();
    let d = |k: usize| p[ring[k] as usize] - p[v];
    let normal = if !boundary {
        let (mut s, mut t) = (Vec3::ZERO, Vec3::ZERO);
        for k in 0..n {
            let angle = 2.0 * PI * k as f32 / n as f32;
            s += angle.cos() * d(k);
            t += angle.sin() * d(k);
        }
        // Our ring runs counter-clockwise where pbrt's runs clockwise
        s.cross(t)
    } else {
        // Along the boundary, then into the surface
        let s = d(n - 1) - d(0);
        let t = match n {
            2 => d(0) + d(1),
            3 => d(1),
            4 => -d(0) + 2.0 * d(1) + 2.0 * d(2) - d(3),
            _ => {
                let theta = PI / (n - 1) as f32;
                let mut t = theta.sin() * (d(0) + d(n - 1));
                for k in 1..n - 1 {
                    t += (2.0 * theta.cos() - 2.0) * (k as f32 * theta).sin() * d(k);
                }
                -t
            }
        };
        // pbrt's s x t points against the winding; same ring order as ours
        t.cross(s)
    };
    let normal = normal.normalize_or_zero();
    if normal != Vec3::ZERO {
        return normal;
    }
    // Degenerate control geometry: fall back to the fan's area-weighted normal
    let fan = if boundary { n - 1 } else { n };
    (0..fan)
        .map(|k| d(k).cross(d((k + 1) % n)))
        .sum::<Vec3>()
        .normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::HashSet;

    fn v(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3::new(x, y, z)
    }

    /// Regular octahedron of circumradius 1, wound outward.
    fn octahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p = vec![
            v(1.0, 0.0, 0.0),
            v(-1.0, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
            v(0.0, -1.0, 0.0),
            v(0.0, 0.0, 1.0),
            v(0.0, 0.0, -1.0),
        ];
        let t = vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        (p, t)
    }

    fn tetrahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p = vec![
            v(1.0, 1.0, 1.0),
            v(1.0, -1.0, -1.0),
            v(-1.0, 1.0, -1.0),
            v(-1.0, -1.0, 1.0),
        ];
        let t = vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
        (p, t)
    }

    /// A w x h grid of unit squares in z = 0, wound counter-clockwise seen
    /// from +z.
    fn grid(w: u32, h: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for y in 0..=h {
            for x in 0..=w {
                p.push(v(x as f32, y as f32, 0.0));
            }
        }
        let mut t = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let a = y * (w + 1) + x;
                t.push([a, a + 1, a + w + 2]);
                t.push([a, a + w + 2, a + w + 1]);
            }
        }
        (p, t)
    }

    fn reversed(t: &[[u32; 3]]) -> Vec<[u32; 3]> {
        t.iter().map(|&[a, b, c]| [a, c, b]).collect()
    }

    fn winding_normal(m: &SubdividedMesh, t: [u32; 3]) -> Vec3 {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        (b - a).cross(c - a)
    }

    fn close(a: Vec3, b: Vec3, eps: f32) -> bool {
        (a - b).abs().max_element() <= eps
    }

    /// Directed edges with how often each occurs.
    fn directed_edges(t: &[[u32; 3]]) -> HashMap<(u32, u32), usize> {
        let mut e = HashMap::new();
        for &[a, b, c] in t {
            for edge in [(a, b), (b, c), (c, a)] {
                *e.entry(edge).or_insert(0) += 1;
            }
        }
        e
    }

    /// Vertices on an edge that only one triangle uses.
    fn boundary_vertices(t: &[[u32; 3]]) -> HashSet<u32> {
        let e = directed_edges(t);
        e.keys()
            .filter(|&&(a, b)| !e.contains_key(&(b, a)))
            .flat_map(|&(a, b)| [a, b])
            .collect()
    }

    #[test]
    fn closed_mesh_counts_follow_euler() {
        for (name, (p, t)) in [("tetrahedron", tetrahedron()), ("octahedron", octahedron())] {
            let (mut nv, mut ne, mut nf) = (p.len(), 3 * t.len() / 2, t.len());
            for levels in 0..=3 {
                let m = loop_subdivide(levels, &p, &t).unwrap();
                assert_eq!(m.triangles.len(), t.len() * 4usize.pow(levels), "{name} {levels}");
                assert_eq!(m.triangles.len(), nf, "{name} {levels}");
                assert_eq!(m.positions.len(), nv, "{name} {levels}");
                assert_eq!(m.normals.len(), nv, "{name} {levels}");
                // Closed and consistently wound: every directed edge once, with its reverse
                let e = directed_edges(&m.triangles);
                assert!(
                    e.iter().all(|(&(a, b), &n)| n == 1 && e.get(&(b, a)) == Some(&1)),
                    "{name} {levels}"
                );
                assert_eq!(e.len() / 2, ne, "{name} {levels}");
                assert_eq!(nv as i64 - ne as i64 + nf as i64, 2);
                // Each level adds a vertex per edge, splits each edge in two and adds three inside each face
                (nv, ne, nf) = (nv + ne, 2 * ne + 3 * nf, 4 * nf);
            }
        }
    }

    #[test]
    fn one_level_applies_loops_masks() {
        // Octahedron: every vertex interior with valence 4, beta = 3/32
        let (p, t) = octahedron();
        let m = HalfEdgeMesh::new(&p, &t).unwrap().refine();
        assert!(close(m.positions[0], v(0.625, 0.0, 0.0), 1e-6), "{}", m.positions[0]);
        // The first edge vertex sits on triangle 0's edge (x, y): 3/8 + 3/8 along it, 1/8 + 1/8 from +z and -z
        assert!(close(m.positions[6], v(0.375, 0.375, 0.0), 1e-6), "{}", m.positions[6]);

        // One triangle: all boundary, 3/4 + 1/8 + 1/8 and midpoints
        let p = vec![v(0.0, 0.0, 0.0), v(8.0, 0.0, 0.0), v(0.0, 8.0, 0.0)];
        let m = HalfEdgeMesh::new(&p, &[[0, 1, 2]]).unwrap().refine();
        assert!(close(m.positions[0], v(1.0, 1.0, 0.0), 1e-6));
        assert!(close(m.positions[1], v(6.0, 1.0, 0.0), 1e-6));
        assert!(close(m.positions[3], v(4.0, 0.0, 0.0), 1e-6));
        assert!(close(m.positions[4], v(4.0, 4.0, 0.0), 1e-6));
        assert_eq!(m.triangles, vec![[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]]);

        // A boundary vertex with interior neighbours ignores them
        let (mut p, t) = grid(2, 1);
        p[4].z = 5.0; // an interior neighbour of vertex 1, the bottom row's middle
        p[1].z = 3.0;
        let m = HalfEdgeMesh::new(&p, &t).unwrap().refine();
        assert!(
            close(m.positions[1], v(1.0, 0.0, 0.75 * 3.0), 1e-6),
            "{}",
            m.positions[1]
        );
    }

    #[test]
    fn level_zero_still_moves_vertices_to_the_limit() {
        // Boundary limit mask 3/5, 1/5, 1/5
        let p = vec![v(0.0, 0.0, 0.0), v(5.0, 0.0, 0.0), v(0.0, 5.0, 0.0)];
        let m = loop_subdivide(0, &p, &[[0, 1, 2]]).unwrap();
        assert!(close(m.positions[0], v(1.0, 1.0, 0.0), 1e-6), "{}", m.positions[0]);
        assert!(close(m.positions[1], v(3.0, 1.0, 0.0), 1e-6), "{}", m.positions[1]);
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        for n in &m.normals {
            assert!(close(*n, Vec3::Z, 1e-6), "{n}");
        }
    }

    #[test]
    fn unused_vertices_are_dropped_and_the_rest_keep_their_order() {
        let p = vec![v(0.0, 0.0, 0.0), v(9.0, 9.0, 9.0), v(5.0, 0.0, 0.0), v(0.0, 5.0, 0.0)];
        let m = loop_subdivide(0, &p, &[[0, 2, 3]]).unwrap();
        assert_eq!(m.positions.len(), 3);
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert!(close(m.positions[1], v(3.0, 1.0, 0.0), 1e-6));
    }

    #[test]
    fn planar_grid_stays_flat_with_normals_along_the_winding() {
        let (p, t) = grid(4, 2);
        for (t, side) in [(t.clone(), 1.0), (reversed(&t), -1.0)] {
            let m = loop_subdivide(3, &p, &t).unwrap();
            assert_eq!(m.triangles.len(), t.len() * 64);
            for (q, n) in m.positions.iter().zip(&m.normals) {
                assert_eq!(q.z, 0.0);
                assert!(close(*n, side * Vec3::Z, 1e-5), "{q}: {n}");
            }
            for &tri in &m.triangles {
                assert!(winding_normal(&m, tri).z * side > 0.0);
            }
        }
    }

    #[test]
    fn straight_boundary_stays_straight() {
        // The bottom row's limit curve between x = 1 and x = 3 is a B-spline
        // of collinear control points; the corners round off
        let (p, t) = grid(4, 2);
        let m = loop_subdivide(3, &p, &t).unwrap();
        let bottom: Vec<Vec3> = boundary_vertices(&m.triangles)
            .into_iter()
            .map(|i| m.positions[i as usize])
            .filter(|q| q.y < 0.5 && (1.0..=3.0).contains(&q.x))
            .collect();
        assert!(bottom.len() >= 16, "{}", bottom.len());
        assert!(bottom.iter().all(|q| q.y.abs() < 1e-6), "{bottom:?}");
        // The corner leaves its place: the boundary rule pulls it along both sides
        let corner = m.positions[0];
        assert!(corner.x > 0.05 && corner.y > 0.05, "{corner}");
    }

    #[test]
    fn octahedron_limit_is_symmetric_and_matches_the_valence_4_mask() {
        // Valence 4: beta = 3/32, gamma = 1 / (4 + 3 / (8 beta)) = 1/8, so the
        // limit is p / 2 + (sum of the four neighbours) / 8 = p / 2
        let gamma = 1.0 / (4.0 + 3.0 / (8.0 * (3.0 / 32.0)));
        assert_eq!(gamma, 0.125);
        let (p, t) = octahedron();
        for levels in 0..=3 {
            let m = loop_subdivide(levels, &p, &t).unwrap();
            for (i, &control) in p.iter().enumerate() {
                let expected = (1.0 - 4.0 * gamma) * control;
                assert!(close(m.positions[i], expected, 1e-5), "{levels}: {}", m.positions[i]);
                assert!(close(m.normals[i], control, 1e-5), "{levels}: {}", m.normals[i]);
            }
            for (q, n) in m.positions.iter().zip(&m.normals) {
                assert!(n.dot(*q) > 0.0, "{levels}: {q} {n}");
                assert!((n.length() - 1.0).abs() < 1e-5);
            }
            for &tri in &m.triangles {
                let [a, b, c] = tri.map(|i| m.positions[i as usize]);
                assert!(winding_normal(&m, tri).dot(a + b + c) > 0.0);
            }
        }
    }

    #[test]
    fn normals_follow_the_winding_not_the_shape() {
        let (p, t) = octahedron();
        let m = loop_subdivide(2, &p, &reversed(&t)).unwrap();
        for (q, n) in m.positions.iter().zip(&m.normals) {
            assert!(n.dot(*q) < 0.0, "{q} {n}");
        }
        for &tri in &m.triangles {
            let [a, b, c] = tri.map(|i| m.positions[i as usize]);
            assert!(winding_normal(&m, tri).dot(a + b + c) < 0.0);
        }
    }

    #[test]
    fn normals_agree_with_the_triangles_around_them() {
        // Closed (interior masks) and open (the boundary masks of each valence)
        let (p, t) = octahedron();
        let (half, top) = (p[..5].to_vec(), t[..4].to_vec());
        let (mut gp, gt) = grid(4, 3);
        for q in &mut gp {
            q.z = 0.3 * (q.x - 2.0).powi(2) - 0.2 * (q.y - 1.5).powi(2);
        }
        // A boundary vertex with six triangles (valence 7) on a curved fan
        let mut fp = vec![v(0.0, 0.0, 0.0)];
        fp.extend((0..=6).map(|k| {
            let a = PI * k as f32 / 6.0;
            v(a.cos(), a.sin(), 0.3 * a.sin())
        }));
        let ft: Vec<[u32; 3]> = (1..=6).map(|k| [0, k, k + 1]).collect();
        for (name, p, t) in [
            ("octahedron", p, t),
            ("half octahedron", half, top),
            ("saddle", gp, gt),
            ("fan", fp, ft),
        ] {
            for levels in 0..=3 {
                let m = loop_subdivide(levels, &p, &t).unwrap();
                let mut around = vec![Vec3::ZERO; m.positions.len()];
                for &tri in &m.triangles {
                    let n = winding_normal(&m, tri).normalize();
                    for i in tri {
                        around[i as usize] += n;
                    }
                }
                for (i, n) in m.normals.iter().enumerate() {
                    let cos = n.dot(around[i].normalize());
                    assert!(cos > 0.8, "{name} level {levels} vertex {i}: cos {cos}");
                }
            }
        }
    }

    #[test]
    fn matches_pbrts_values_on_a_saddle_and_a_fan() {
        // Expected: a line-by-line transcription of pbrt-v4's LoopSubdivide in
        // double precision, normals normalised and negated (see loop_subdivide)
        let (mut p, t) = grid(4, 3);
        for q in &mut p {
            q.z = 0.3 * (q.x - 2.0).powi(2) - 0.2 * (q.y - 1.5).powi(2);
        }
        let m = loop_subdivide(1, &p, &t).unwrap();
        let expected = [
            // Boundary valence 3, 4 and 2, interior 6, and the first edge vertex (boundary, 4)
            (0, v(0.175, 0.175, 0.6625), v(0.63027, -0.27655, 0.72545)),
            (2, v(2.0, 0.0, -0.345), v(0.0, -0.34975, 0.93684)),
            (4, v(3.825, 0.175, 0.6625), v(-0.6267, -0.28156, 0.72661)),
            (7, v(2.0, 1.0, -0.01667), v(0.0, -0.18824, 0.98212)),
            (20, v(0.525, 0.025, 0.3025), v(0.58829, -0.28545, 0.75659)),
        ];
        for (i, position, normal) in expected {
            assert!(close(m.positions[i], position, 1e-4), "{i}: {}", m.positions[i]);
            assert!(close(m.normals[i], normal, 1e-4), "{i}: {}", m.normals[i]);
        }

        // A boundary vertex of valence 7 (the general boundary tangent)
        let mut p = vec![v(0.0, 0.0, 0.0)];
        p.extend((0..=6).map(|k| {
            let a = PI * k as f32 / 6.0;
            v(a.cos(), a.sin(), 0.3 * a.sin())
        }));
        let t: Vec<[u32; 3]> = (1..=6).map(|k| [0, k, k + 1]).collect();
        let m = loop_subdivide(1, &p, &t).unwrap();
        assert!(
            close(m.positions[1], v(0.80155, 0.0875, 0.02625), 1e-4),
            "{}",
            m.positions[1]
        );
        assert!(close(m.normals[0], v(0.0, -0.28735, 0.95783), 1e-4), "{}", m.normals[0]);
    }

    #[test]
    fn bad_input_is_refused_with_the_right_error() {
        use SubdivisionError::*;
        let (p, t) = octahedron();
        let e = |levels, p: &[Vec3], t: &[[u32; 3]]| loop_subdivide(levels, p, t).unwrap_err();

        assert_eq!(e(1, &p, &[]), NoTriangles);
        assert_eq!(
            e(1, &p, &[[0, 2, 4], [0, 6, 4]]),
            IndexOutOfRange {
                face: 1,
                index: 6,
                vertices: 6
            }
        );
        assert_eq!(
            e(1, &p, &[[0, 2, 4], [3, 3, 4]]),
            DegenerateFace {
                face: 1,
                indices: [3, 3, 4]
            }
        );
        // A fin: edge (0, 4) shared by three triangles
        assert_eq!(
            e(1, &p, &[[0, 2, 4], [4, 3, 0], [1, 0, 4]]),
            NonManifoldEdge { a: 0, b: 4, face: 2 }
        );
        // Two triangles running 0 -> 2 along their shared edge
        assert_eq!(
            e(1, &p, &[[0, 2, 4], [0, 2, 5]]),
            InconsistentOrientation {
                a: 0,
                b: 2,
                first: 0,
                second: 1
            }
        );
        let mut flipped = t.clone();
        flipped[5] = [1, 5, 2];
        assert!(matches!(e(2, &p, &flipped), InconsistentOrientation { .. }));
        // A bow tie: two triangles that share only vertex 4
        assert_eq!(e(1, &p, &[[0, 2, 4], [1, 3, 4]]), NonManifoldVertex { vertex: 4 });
        // 8 x 4^11 = 2^25 triangles
        assert_eq!(e(11, &p, &t), TooManyLevels { levels: 11, faces: 8 });
        assert_eq!(check_size(12, 1), Ok(()));
        assert!(check_size(13, 1).is_err());
        assert_eq!(
            e(u32::MAX, &p, &t),
            TooManyLevels {
                levels: u32::MAX,
                faces: 8
            }
        );
        let message = e(12, &p, &t).to_string();
        assert!(
            message.contains("12 levels") && message.contains("16777216"),
            "{message}"
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        #[test]
        fn arbitrary_input_never_panics(
            tris in prop::collection::vec(prop::array::uniform3(0u32..9), 1..10),
            coords in prop::collection::vec(-2.0f32..2.0, 24),
            levels in 0u32..3,
        ) {
            let p: Vec<Vec3> = coords.chunks(3).map(Vec3::from_slice).collect();
            if let Ok(m) = loop_subdivide(levels, &p, &tris) {
                prop_assert_eq!(m.triangles.len(), tris.len() * 4usize.pow(levels));
                prop_assert_eq!(m.normals.len(), m.positions.len());
                prop_assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < m.positions.len()));
            }
        }
    }
}
