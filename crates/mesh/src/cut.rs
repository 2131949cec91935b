//! Cuts: strokes that separate a shape along them, so that parts of a flat picture
//! that touch (a tail against a leg) can move apart.
//!
//! A cut is meshed as a constraint polyline ([`clip_to_domain`] keeps the parts of a
//! stroke inside the shape, ending exactly on its boundary where the stroke leaves it),
//! then [`split_along`] doubles the vertices along it: each vertex on a cut gets one
//! copy per side, so no triangle edge crosses the cut, a graph distance goes around it,
//! and the two sides move independently. A cut that ends inside the shape leaves the
//! shape joined past its end.

use glam::DVec2;

use crate::{Domain, Mesh};

/// The pieces of the polyline `stroke` that lie inside `domain`, in stroke order: where
/// the stroke crosses a ring, a piece ends (or starts) at the crossing itself. Pieces
/// shorter than a thousandth of a pixel are dropped.
pub fn clip_to_domain(domain: &Domain, stroke: &[DVec2]) -> Vec<Vec<DVec2>> {
    let rings: Vec<&[DVec2]> = domain.rings().collect();
    let mut pieces = Vec::new();
    let mut current: Vec<DVec2> = Vec::new();
    let mut finish = |current: &mut Vec<DVec2>| {
        current.dedup_by(|a, b| a.distance(*b) < 1e-9);
        let length: f64 = current.windows(2).map(|w| w[0].distance(w[1])).sum();
        if current.len() >= 2 && length >= 1e-3 {
            pieces.push(std::mem::take(current));
        } else {
            current.clear();
        }
    };
    for pair in stroke.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        // Where the segment crosses the rings: fractions along it, and the crossing
        // taken on the ring's own edge (so that it lies on the boundary exactly).
        let mut cuts = Vec::new();
        for ring in &rings {
            for (i, &p) in ring.iter().enumerate() {
                let q = ring[(i + 1) % ring.len()];
                if let Some((t, u)) = crossing(a, b, p, q) {
                    let at = if u <= 1e-12 {
                        p
                    } else if u >= 1.0 - 1e-12 {
                        q
                    } else {
                        p.lerp(q, u)
                    };
                    cuts.push((t, at));
                }
            }
        }
        // The segment's own ends last, so that where one lies on a ring the crossing
        // (exactly on the ring) is what the stable sort and the dedup keep.
        cuts.extend([(0.0, a), (1.0, b)]);
        cuts.sort_by(|x, y| x.0.total_cmp(&y.0));
        cuts.dedup_by(|x, y| (x.0 - y.0).abs() < 1e-12);
        for span in cuts.windows(2) {
            let ((s, from), (t, to)) = (span[0], span[1]);
            let inside = domain.contains(a.lerp(b, 0.5 * (s + t)));
            if inside {
                if current.is_empty() {
                    current.push(from);
                }
                current.push(to);
            } else {
                finish(&mut current);
            }
        }
    }
    finish(&mut current);
    pieces
}

/// Where segment `a`–`b` crosses segment `p`–`q`, as the fractions along `a`–`b` and
/// along `p`–`q` (`None` when they do not cross or are parallel).
fn crossing(a: DVec2, b: DVec2, p: DVec2, q: DVec2) -> Option<(f64, f64)> {
    let r = b - a;
    let s = q - p;
    let denom = r.perp_dot(s);
    if denom.abs() < 1e-300 {
        return None;
    }
    let t = (p - a).perp_dot(s) / denom;
    let u = (p - a).perp_dot(r) / denom;
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)).then_some((t, u))
}

/// Splits `mesh` along `paths` (chains of vertices joined by mesh edges, such as
/// [`TriangulatedImage::polyline_paths`](crate::TriangulatedImage::polyline_paths)):
/// around each vertex on a path, the triangles that meet it fall into groups joined
/// through edges that are not on a path; each group but the first gets a new copy of
/// the vertex (at the same position, appended). Returns, for each new vertex, the
/// vertex it copies.
///
/// A path through the inside doubles its inner vertices and keeps its ends (the shape
/// stays joined past them); a path reaching the boundary doubles its end there too.
pub fn split_along(mesh: &mut Mesh, paths: &[Vec<u32>]) -> Vec<u32> {
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut cut_edges = std::collections::HashSet::new();
    let mut on_cut = Vec::new();
    for path in paths {
        for pair in path.windows(2) {
            if pair[0] != pair[1] {
                cut_edges.insert(key(pair[0], pair[1]));
            }
        }
        on_cut.extend(path.iter().copied());
    }
    on_cut.sort_unstable();
    on_cut.dedup();
    if cut_edges.is_empty() {
        return Vec::new();
    }
    let mut around: std::collections::HashMap<u32, Vec<usize>> =
        on_cut.iter().map(|&v| (v, Vec::new())).collect();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &v in tri {
            if let Some(list) = around.get_mut(&v) {
                list.push(t);
            }
        }
    }
    let mut copies = Vec::new();
    for &v in &on_cut {
        let fan = &around[&v];
        // Union-find over the fan: two triangles sharing an edge v–w that is not cut.
        let mut parent: Vec<usize> = (0..fan.len()).collect();
        let others = |t: usize| mesh.triangles[t].into_iter().filter(move |&w| w != v);
        for i in 0..fan.len() {
            for j in i + 1..fan.len() {
                let shared = others(fan[i]).find(|w| others(fan[j]).any(|x| x == *w));
                if let Some(w) = shared
                    && !cut_edges.contains(&key(v, w))
                {
                    let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                    parent[a] = b;
                }
            }
        }
        let mut group_vertex: std::collections::HashMap<usize, u32> =
            std::collections::HashMap::new();
        for (i, &t) in fan.iter().enumerate() {
            let group = root(&mut parent, i);
            let first = group_vertex.is_empty();
            let vertex = *group_vertex.entry(group).or_insert_with(|| {
                if first {
                    v
                } else {
                    mesh.vertices.push(mesh.vertices[v as usize]);
                    copies.push(v);
                    (mesh.vertices.len() - 1) as u32
                }
            });
            if vertex != v {
                for corner in &mut mesh.triangles[t] {
                    if *corner == v {
                        *corner = vertex;
                    }
                }
            }
        }
    }
    copies
}

/// The root of `i`'s set in the union-find forest `parent` (paths halved on the way).
fn root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Constraints, MeshOptions, triangulate};

    fn square() -> Domain {
        Domain::full_rectangle(40, 20)
    }

    /// `domain` meshed at about `vertices` vertices with `pieces` as edges.
    fn mesh_along(
        domain: &Domain,
        pieces: &[Vec<DVec2>],
        vertices: usize,
    ) -> crate::TriangulatedImage {
        let options = MeshOptions {
            target_vertices: vertices,
            ..MeshOptions::default()
        };
        let constraints = Constraints {
            points: &[],
            polylines: pieces,
        };
        triangulate(domain, &constraints, &options).expect("meshed")
    }

    #[test]
    fn a_stroke_is_clipped_at_the_boundary() {
        let stroke = [DVec2::new(20.0, -5.0), DVec2::new(20.0, 25.0)];
        let pieces = clip_to_domain(&square(), &stroke);
        assert_eq!(
            pieces,
            vec![vec![DVec2::new(20.0, 0.0), DVec2::new(20.0, 20.0)]]
        );
        // Wholly outside: nothing.
        let outside = [DVec2::new(-5.0, -5.0), DVec2::new(-1.0, 30.0)];
        assert!(clip_to_domain(&square(), &outside).is_empty());
    }

    #[test]
    fn a_cut_across_the_shape_splits_it_in_two() {
        let domain = square();
        let pieces = clip_to_domain(&domain, &[DVec2::new(20.0, -5.0), DVec2::new(20.0, 25.0)]);
        let mut t = mesh_along(&domain, &pieces, 300);
        let along = t.polyline_paths[0].len();
        let copies = split_along(&mut t.mesh, &t.polyline_paths);
        // Every vertex along the cut, its ends on the boundary included, is doubled.
        assert_eq!(copies.len(), along);
        t.mesh.sanity_check().expect("a valid mesh");
        assert_eq!(components(&t.mesh), 2);
    }

    #[test]
    fn strokes_that_double_back_or_start_on_the_outline_mesh_and_split() {
        let domain = square();
        let strokes = [
            // Starts exactly on the outline, doubles back over itself.
            vec![
                DVec2::new(10.0, 0.0),
                DVec2::new(10.0, 12.0),
                DVec2::new(10.0, 6.0),
                DVec2::new(10.0, 20.0),
            ],
            // A zigzag crossing the first.
            vec![
                DVec2::new(0.0, 3.0),
                DVec2::new(15.0, 9.0),
                DVec2::new(5.0, 14.0),
                DVec2::new(30.0, 17.0),
            ],
        ];
        let pieces: Vec<Vec<DVec2>> = strokes
            .iter()
            .flat_map(|s| clip_to_domain(&domain, s))
            .collect();
        let mut t = mesh_along(&domain, &pieces, 400);
        let copies = split_along(&mut t.mesh, &t.polyline_paths);
        t.mesh.sanity_check().expect("a valid mesh");
        assert!(!copies.is_empty());
    }

    #[test]
    fn a_cut_inside_the_shape_leaves_it_joined_past_its_ends() {
        let domain = square();
        let pieces = vec![vec![DVec2::new(20.0, 5.0), DVec2::new(20.0, 15.0)]];
        let mut t = mesh_along(&domain, &pieces, 300);
        let along = t.polyline_paths[0].len();
        let copies = split_along(&mut t.mesh, &t.polyline_paths);
        assert_eq!(copies.len(), along - 2, "the inner vertices only");
        t.mesh.sanity_check().expect("a valid mesh");
        assert_eq!(components(&t.mesh), 1);
    }

    /// Connected pieces of the mesh's edge graph.
    fn components(mesh: &Mesh) -> usize {
        let n = mesh.vertices.len();
        let mut parent: Vec<usize> = (0..n).collect();
        for tri in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (
                    root(&mut parent, tri[k] as usize),
                    root(&mut parent, tri[(k + 1) % 3] as usize),
                );
                parent[a] = b;
            }
        }
        (0..n).filter(|&i| root(&mut parent, i) == i).count()
    }
}
