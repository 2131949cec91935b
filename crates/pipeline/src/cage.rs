//! Local barycentric coordinates of a rig file's cage (the `lbc` crate): the cage's
//! inside triangulated (or a given mesh of it), the coordinates solved, and the
//! posed cage.
//!
//! LBC is a cage method: it moves what lies inside the cage by the cage's vertices;
//! it has no handles. The command line's `render`, `weights`, `deform` and `bench`
//! use it, and so does the editor's cage tool; both mesh the cage's inside to
//! [`cage_vertices`] and draw with [`warp_by_cage`], so the editor's export is what
//! `c2warp render` gives for the saved project. [`cage_from_outline`] makes a cage
//! around a cut-out's visible shape.

use anyhow::{Context, Result, bail, ensure};
use glam::DVec2;
use project::{MAX_CAGE_VERTICES, Method, Project, Tau};

/// Mesh vertices inside a cage when neither a `--density` nor the rig names a count:
/// the solve's time grows quickly with it (a few seconds at this size).
pub const DEFAULT_CAGE_VERTICES: usize = 2000;

/// How many mesh vertices the inside of `project`'s cage is triangulated to: `density`
/// (a command line's `--density`) if given, else the rig's `lbc.density`, else its
/// `density`, else [`DEFAULT_CAGE_VERTICES`].
pub fn cage_vertices(project: &Project, density: Option<usize>) -> usize {
    density
        .or(project.lbc.and_then(|l| l.density))
        .or(project.density)
        .unwrap_or(DEFAULT_CAGE_VERTICES)
}

/// The solver's settings for `tau` (everything else at the `lbc` crate's defaults).
pub fn solver_settings(tau: Tau) -> lbc::Settings {
    lbc::Settings {
        tau: match tau {
            Tau::Square => lbc::Tau::Square,
            Tau::Linear => lbc::Tau::Linear,
            Tau::Constant => lbc::Tau::Constant,
            Tau::Sqrt => lbc::Tau::Sqrt,
        },
        ..lbc::Settings::default()
    }
}

/// Where the mesh of the cage's inside comes from.
pub enum CageMesh {
    /// Triangulate the inside to about this many vertices.
    Triangulate {
        /// Target vertex count.
        target_vertices: usize,
    },
    /// A given triangulation of the inside (e.g. read from an OBJ file); the cage's
    /// vertices are found among its vertices by position.
    Given {
        /// Vertex positions.
        positions: Vec<DVec2>,
        /// Triangles.
        triangles: Vec<[u32; 3]>,
    },
}

/// The solved coordinates of a rig file's cage.
pub struct CageCoordinates {
    /// The mesh of the cage's inside.
    pub domain: lbc::Domain,
    /// Every mesh vertex's compact row: `(cage vertex, weight)` pairs, weights below
    /// `10⁻³/n` dropped and the row renormalised.
    pub weights: lbc::CompactWeights,
    /// Iterations, residuals, objective and times of the solve.
    pub report: lbc::Report,
    /// The paper's locality statistics `P(t)` (at `t` = 0, `10⁻³/n`, 0.01, 0.05, 0.1,
    /// 0.2, …, 1) and `Q(k)`, of the coordinates before compaction.
    pub locality: lbc::Locality,
    /// The posed cage (the rest cage where the rig gives no pose).
    pub pose: Vec<DVec2>,
}

impl CageCoordinates {
    /// Where every mesh vertex goes for the posed cage.
    ///
    /// # Errors
    /// Only on a bug (a pose of the wrong length).
    pub fn deformed(&self) -> Result<Vec<DVec2>> {
        Ok(self.weights.deform(&self.pose)?)
    }
}

/// Solves the local barycentric coordinates of `project`'s cage on `mesh`, telling
/// `progress` each ADMM iteration (it returns `false` to cancel).
///
/// # Errors
/// No cage in the rig file, a cage that is not a simple polygon, a given mesh that
/// does not hold the cage's vertices, or a cancelled solve.
pub fn cage_coordinates(
    project: &Project,
    mesh: CageMesh,
    progress: &mut dyn FnMut(&lbc::Progress) -> bool,
) -> Result<CageCoordinates> {
    let Some(spec) = &project.cage else {
        bail!("the rig has no \"cage\" (LBC warps by a cage)");
    };
    let rest: Vec<DVec2> = spec.rest.iter().map(|&p| DVec2::from(p)).collect();
    let pose: Vec<DVec2> = spec.pose.as_ref().map_or_else(
        || rest.clone(),
        |p| p.iter().map(|&q| DVec2::from(q)).collect(),
    );
    let cage = lbc::Cage::new(rest).context("the rig's cage")?;
    let domain = match mesh {
        CageMesh::Triangulate { target_vertices } => {
            lbc::Domain::triangulate(&cage, target_vertices)
                .context("cannot triangulate the cage")?
        }
        CageMesh::Given {
            positions,
            triangles,
        } => lbc::Domain::from_mesh(&cage, positions, triangles)
            .context("the mesh does not fit the cage")?,
    };
    let settings = solver_settings(project.lbc.unwrap_or_default().tau);
    let coordinates = lbc::solve(&domain, &settings, progress)?;
    let report = coordinates.report.clone();
    let n = coordinates.cage_vertices().max(1) as f64;
    let mut t = vec![0.0, 1e-3 / n, 0.01, 0.05];
    t.extend((1..=10).map(|k| f64::from(k) / 10.0));
    let locality = lbc::locality(&domain, &coordinates, &t);
    Ok(CageCoordinates {
        weights: coordinates.compact(),
        domain,
        report,
        locality,
        pose,
    })
}

/// Whether `project` (with `method` overriding its own) warps by a cage.
pub fn uses_cage(project: &Project, method: Option<Method>) -> bool {
    method.unwrap_or(project.method) == Method::Lbc
}

/// The picture warped by a cage, as GIMP's cage tool does it: what lies inside the
/// rest cage is taken out and drawn where the posed cage takes it; what lies outside
/// stays as it is, and shows wherever the warped inside does not cover it (the warped
/// inside is drawn over it, alpha blended). Drawn on the CPU at full resolution, 8 bits
/// per channel.
///
/// # Errors
/// Non-finite deformed positions, or a picture too large to draw.
pub fn warp_by_cage(
    image: &image::RgbaImage,
    solved: &CageCoordinates,
) -> Result<image::RgbaImage> {
    warp_by_cage_posed(image, solved, &solved.pose)
}

/// As [`warp_by_cage`], with the cage in `pose` (one point per cage vertex) rather
/// than the pose it was solved with.
///
/// # Errors
/// A pose of the wrong length, non-finite deformed positions, or a picture too large
/// to draw.
pub fn warp_by_cage_posed(
    image: &image::RgbaImage,
    solved: &CageCoordinates,
    pose: &[DVec2],
) -> Result<image::RgbaImage> {
    let deformed = solved.weights.deform(pose)?;
    if deformed.iter().any(|p| !p.is_finite()) {
        bail!("the cage sent a vertex to a non-finite position");
    }
    let rest = rest_positions(solved);
    let deformed: Vec<glam::Vec2> = deformed.iter().map(|p| p.as_vec2()).collect();
    let (w, h) = image.dimensions();
    let layer = render::warp_cpu(
        image,
        &render::WarpMesh {
            rest: &rest,
            deformed: &deformed,
            triangles: solved.domain.triangles(),
        },
        w,
        h,
        &render::RasterOptions::default(),
    )?;
    Ok(composite(image, solved, &layer))
}

/// As [`warp_by_cage`], with the inside drawn on a GPU (or a software adapter) by the
/// skinning shader the C² weights use: the compact rows are its weight rows and each
/// cage vertex a node whose transform has no linear part and the posed vertex as its
/// translation ([`skinning_table`], [`pose_transforms`]).
///
/// # Errors
/// No usable adapter, non-finite pose, or a picture too large for the device.
pub fn warp_by_cage_gpu(
    image: &image::RgbaImage,
    solved: &CageCoordinates,
) -> Result<image::RgbaImage> {
    if solved.pose.iter().any(|p| !p.is_finite()) {
        bail!("the cage's pose is not finite");
    }
    let gpu = render::GpuContext::new()?;
    let rest = rest_positions(solved);
    let (rows, nodes, weights) = skinning_table(&solved.weights);
    let (w, h) = image.dimensions();
    let layer = gpu.warp_skinned(
        image,
        &render::SkinnedMesh {
            rest: &rest,
            rows: &rows,
            nodes: &nodes,
            weights: &weights,
            triangles: solved.domain.triangles(),
        },
        &pose_transforms(&solved.pose),
        w,
        h,
    )?;
    Ok(composite(image, solved, &layer))
}

/// The compact rows as a skinning shader reads them: row `v` is
/// `nodes[rows[v]..rows[v + 1]]` with `weights` alongside (cage vertex indices and
/// their weights), as [`render::SkinnedMesh`] takes them.
pub fn skinning_table(weights: &lbc::CompactWeights) -> (Vec<u32>, Vec<u32>, Vec<f32>) {
    let mut rows = Vec::with_capacity(weights.vertices() + 1);
    let mut nodes = Vec::with_capacity(weights.len());
    let mut values = Vec::with_capacity(weights.len());
    rows.push(0);
    for v in 0..weights.vertices() {
        for &(k, w) in weights.row(v) {
            nodes.push(k);
            values.push(w as f32);
        }
        rows.push(nodes.len() as u32);
    }
    (rows, nodes, values)
}

/// The node transforms that pose a cage in the skinning shader: no linear part, the
/// posed vertex as the translation, so that `Σ wᵢ (Aᵢ x + tᵢ) = Σ wᵢ cᵢ'`.
pub fn pose_transforms(pose: &[DVec2]) -> Vec<render::Affine> {
    pose.iter()
        .map(|p| [0.0, 0.0, 0.0, 0.0, p.x as f32, p.y as f32])
        .collect()
}

/// The mesh's rest positions, in single precision for drawing.
fn rest_positions(solved: &CageCoordinates) -> Vec<glam::Vec2> {
    solved
        .domain
        .positions()
        .iter()
        .map(|p| p.as_vec2())
        .collect()
}

/// `layer` (the warped inside) over `image` with the inside of the rest cage cleared.
fn composite(
    image: &image::RgbaImage,
    solved: &CageCoordinates,
    layer: &image::RgbaImage,
) -> image::RgbaImage {
    let mut out = image.clone();
    clear_inside(&mut out, solved.domain.cage().vertices());
    for (base, top) in out.pixels_mut().zip(layer.pixels()) {
        *base = over(top.0, base.0).into();
    }
    out
}

/// Makes every pixel whose centre lies inside the polygon `cage` transparent (even-odd
/// rule, one scan line per row): the picture outside a cage, as [`warp_by_cage`] keeps
/// it.
pub fn clear_inside(image: &mut image::RgbaImage, cage: &[DVec2]) {
    let (w, h) = image.dimensions();
    let mut crossings = Vec::new();
    for y in 0..h {
        let cy = f64::from(y) + 0.5;
        crossings.clear();
        for (i, &a) in cage.iter().enumerate() {
            let b = cage[(i + 1) % cage.len()];
            if (a.y <= cy) != (b.y <= cy) {
                crossings.push(a.x + (cy - a.y) / (b.y - a.y) * (b.x - a.x));
            }
        }
        crossings.sort_by(f64::total_cmp);
        for span in crossings.chunks_exact(2) {
            // Pixels whose centre x + 0.5 lies in [span[0], span[1]).
            let first = (span[0] - 0.5).ceil().max(0.0);
            let last = (span[1] - 0.5).ceil().min(f64::from(w));
            let (first, last) = (first as u32, last as u32);
            for x in first..last.max(first) {
                image.put_pixel(x, y, image::Rgba([0, 0, 0, 0]));
            }
        }
    }
}

/// `top` over `base`, straight (not premultiplied) alpha.
fn over(top: [u8; 4], base: [u8; 4]) -> [u8; 4] {
    let (ta, ba) = (f32::from(top[3]) / 255.0, f32::from(base[3]) / 255.0);
    let a = ta + ba * (1.0 - ta);
    if a <= 0.0 {
        return [0; 4];
    }
    let mut out = [0u8; 4];
    for c in 0..3 {
        let v = (f32::from(top[c]) * ta + f32::from(base[c]) * ba * (1.0 - ta)) / a;
        out[c] = v.round().clamp(0.0, 255.0) as u8;
    }
    out[3] = (a * 255.0).round() as u8;
    out
}

/// A cage around `image`'s visible shape (every pixel with alpha > 0; for an opaque
/// picture, the picture's rectangle), as a user would click it: the outline of the
/// largest piece, `offset` pixels outside it, simplified to `vertices` vertices.
///
/// The alpha mask is dilated by `offset` pixels and traced ([`mesh::domain_from_image`]
/// with that simplification tolerance, so the outline runs 0 to about `2·offset` pixels
/// outside the visible pixels); vertices are then removed smallest triangle first
/// (Visvalingam–Whyatt), never one whose removal would make two edges cross, and edges
/// split at their middle while the outline has fewer vertices than asked. Removing a
/// convex vertex cuts a corner, so with few vertices a long-limbed shape's extremities
/// may stick out of the cage (and stay as they are when it is posed).
///
/// # Errors
/// `vertices` outside 3 to [`MAX_CAGE_VERTICES`], a non-finite or negative `offset`,
/// a picture without a visible pixel, or an outline that cannot be brought down to
/// `vertices` vertices as a simple polygon.
pub fn cage_from_outline(
    image: &image::RgbaImage,
    vertices: usize,
    offset: f64,
) -> Result<Vec<DVec2>> {
    ensure!(
        (3..=MAX_CAGE_VERTICES).contains(&vertices),
        "a cage needs 3 to {MAX_CAGE_VERTICES} vertices, not {vertices}"
    );
    ensure!(
        offset.is_finite() && offset >= 0.0,
        "the cage's offset must be a number of pixels, not {offset}"
    );
    let options = mesh::DomainOptions {
        simplify_tolerance: offset.max(0.75),
        // Holes do not matter: only the outer ring is used.
        min_hole_area: f64::MAX,
        ..mesh::DomainOptions::default()
    };
    let domain = mesh::domain_from_image(image, &options)
        .context("the picture has no visible pixel to put a cage around")?;
    let outline = domain
        .polygons
        .iter()
        .map(|p| &p.outer)
        .max_by(|a, b| ring_area(a).total_cmp(&ring_area(b)))
        .context("the picture has no outline")?;
    let mut ring = fewer_vertices(outline.clone(), vertices);
    ensure!(
        ring.len() <= vertices,
        "the outline cannot be simplified to {vertices} vertices without its edges \
         crossing (it keeps {}): ask for more",
        ring.len()
    );
    split_longest_edges(&mut ring, vertices);
    lbc::Cage::new(ring.clone()).context("the outline does not make a simple cage")?;
    Ok(ring)
}

fn ring_area(ring: &[DVec2]) -> f64 {
    let n = ring.len();
    0.5 * (0..n)
        .map(|i| ring[i].perp_dot(ring[(i + 1) % n]))
        .sum::<f64>()
        .abs()
}

/// Visvalingam–Whyatt on a closed ring: removes the vertex whose triangle with its
/// neighbours is smallest, until `target` are left, skipping removals that would make
/// the new edge touch another. Stops early (more than `target` left) when every
/// remaining removal would.
fn fewer_vertices(ring: Vec<DVec2>, target: usize) -> Vec<DVec2> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    let n = ring.len();
    if n <= target.max(3) {
        return ring;
    }
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let mut alive = vec![true; n];
    let mut stamp = vec![0u32; n];
    let cost = |prev: &[usize], next: &[usize], i: usize| {
        let (a, b, c) = (ring[prev[i]], ring[i], ring[next[i]]);
        0.5 * (b - a).perp_dot(c - a).abs()
    };
    // Costs as ordered integers (areas are finite and non-negative): f64 bits order
    // the same way for non-negative numbers.
    let mut heap: BinaryHeap<Reverse<(u64, u32, usize)>> = (0..n)
        .map(|i| Reverse((cost(&prev, &next, i).to_bits(), 0, i)))
        .collect();
    let mut left = n;
    while left > target
        && let Some(Reverse((_, s, i))) = heap.pop()
    {
        if !alive[i] || s != stamp[i] {
            continue;
        }
        let (a, c) = (ring[prev[i]], ring[next[i]]);
        // The new edge a–c may touch no edge but the ones it meets at a and c.
        let mut k = next[i];
        let mut crosses = false;
        while next[k] != prev[i] {
            let (p, q) = (ring[k], ring[next[k]]);
            if k != next[i] && segments_touch(a, c, p, q) {
                crosses = true;
                break;
            }
            k = next[k];
        }
        // Edges next to the new one must not fold back over it.
        crosses |= folds(a, c, ring[next[next[i]]]) || folds(c, a, ring[prev[prev[i]]]);
        if crosses || left <= 3 {
            // Tried again when a neighbour goes and its triangle changes.
            continue;
        }
        alive[i] = false;
        left -= 1;
        let (p, q) = (prev[i], next[i]);
        next[p] = q;
        prev[q] = p;
        for j in [p, q] {
            stamp[j] += 1;
            heap.push(Reverse((cost(&prev, &next, j).to_bits(), stamp[j], j)));
        }
    }
    let start = (0..n).find(|&i| alive[i]).unwrap_or(0);
    let mut out = vec![ring[start]];
    let mut k = next[start];
    while k != start {
        out.push(ring[k]);
        k = next[k];
    }
    out
}

/// Whether the closed segments `ab` and `cd` share a point.
fn segments_touch(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let orient = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let on = |p: DVec2, q: DVec2, r: DVec2| {
        orient(p, q, r) == 0.0
            && r.x >= p.x.min(q.x)
            && r.x <= p.x.max(q.x)
            && r.y >= p.y.min(q.y)
            && r.y <= p.y.max(q.y)
    };
    let (o1, o2, o3, o4) = (
        orient(a, b, c),
        orient(a, b, d),
        orient(c, d, a),
        orient(c, d, b),
    );
    (o1 * o2 < 0.0 && o3 * o4 < 0.0) || on(a, b, c) || on(a, b, d) || on(c, d, a) || on(c, d, b)
}

/// Whether the edge from `b` to `d`, following the edge `a → b`, turns back onto it.
fn folds(a: DVec2, b: DVec2, d: DVec2) -> bool {
    (b - a).perp_dot(d - b) == 0.0 && (b - a).dot(d - b) < 0.0
}

/// Splits the longest edge at its middle until `ring` has `target` vertices.
fn split_longest_edges(ring: &mut Vec<DVec2>, target: usize) {
    while ring.len() < target {
        let n = ring.len();
        let Some(longest) = (0..n).max_by(|&i, &j| {
            let len = |k: usize| ring[k].distance_squared(ring[(k + 1) % n]);
            len(i).total_cmp(&len(j))
        }) else {
            return;
        };
        let middle = (ring[longest] + ring[(longest + 1) % n]) * 0.5;
        ring.insert(longest + 1, middle);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn pose_transforms_translate_by_the_posed_vertex() {
        let a = super::pose_transforms(&[DVec2::new(3.0, -4.0)]);
        assert_eq!(a, vec![[0.0, 0.0, 0.0, 0.0, 3.0, -4.0]]);
    }

    use super::*;

    /// A disc and a thin bar off it, as a cut-out.
    fn cut_out() -> image::RgbaImage {
        image::RgbaImage::from_fn(200, 160, |x, y| {
            let (fx, fy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            let disc = (fx - 80.0).hypot(fy - 80.0) < 50.0;
            let bar = (120.0..180.0).contains(&fx) && (70.0..90.0).contains(&fy);
            image::Rgba([10, 200, 30, if disc || bar { 255 } else { 0 }])
        })
    }

    #[test]
    fn an_outline_cage_has_the_vertices_asked_for_and_encloses_most_of_the_shape() {
        let image = cut_out();
        for n in [6, 16, 40] {
            let ring = cage_from_outline(&image, n, 6.0).expect("a cage");
            assert_eq!(ring.len(), n);
            let cage = lbc::Cage::new(ring.clone()).expect("simple");
            // Outside the shape: no vertex on a visible pixel.
            for p in &ring {
                let (x, y) = (p.x.floor() as u32, p.y.floor() as u32);
                if x < 200 && y < 160 {
                    assert_eq!(image.get_pixel(x, y).0[3], 0, "vertex {p} on the shape");
                }
            }
            let (mut inside, mut visible) = (0, 0);
            for (x, y, px) in image.enumerate_pixels() {
                if px.0[3] > 0 {
                    visible += 1;
                    let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                    inside += usize::from(cage.contains(c));
                }
            }
            let share = inside as f64 / visible as f64;
            // Six vertices must cut the disc's sides; sixteen are enough for all of it.
            let least = if n < 10 { 0.9 } else { 0.999 };
            assert!(share > least, "{n} vertices enclose {share} of the shape");
        }
    }

    #[test]
    fn an_opaque_picture_gets_its_rectangle_split_evenly() {
        let image = image::RgbaImage::from_pixel(100, 50, image::Rgba([1, 2, 3, 255]));
        let ring = cage_from_outline(&image, 12, 4.0).expect("a cage");
        assert_eq!(ring.len(), 12);
        let cage = lbc::Cage::new(ring.clone()).expect("simple");
        assert!((cage.area() - 5000.0).abs() < 1e-9);
        assert!(
            ring.iter()
                .all(|p| p.x >= 0.0 && p.x <= 100.0 && p.y >= 0.0 && p.y <= 50.0)
        );
    }

    #[test]
    fn bad_requests_are_refused() {
        let image = cut_out();
        assert!(cage_from_outline(&image, 2, 4.0).is_err());
        assert!(cage_from_outline(&image, 5000, 4.0).is_err());
        assert!(cage_from_outline(&image, 8, f64::NAN).is_err());
        assert!(cage_from_outline(&image::RgbaImage::new(30, 30), 8, 4.0).is_err());
    }

    #[test]
    fn cage_density_follows_the_command_line_then_lbc_then_the_rig() {
        let mut project = Project::default();
        assert_eq!(cage_vertices(&project, None), DEFAULT_CAGE_VERTICES);
        project.density = Some(5000);
        assert_eq!(cage_vertices(&project, None), 5000);
        project.lbc = Some(project::LbcSettings {
            density: Some(300),
            ..Default::default()
        });
        assert_eq!(cage_vertices(&project, None), 300);
        assert_eq!(cage_vertices(&project, Some(700)), 700);
    }

    #[test]
    fn a_posed_warp_moves_the_inside_and_keeps_the_outside() {
        let image = image::RgbaImage::from_fn(60, 40, |x, y| {
            image::Rgba([(x * 4) as u8, (y * 6) as u8, 90, 255])
        });
        let project = Project {
            method: Method::Lbc,
            cage: Some(project::CageSpec {
                rest: vec![[10.0, 10.0], [40.0, 10.0], [40.0, 30.0], [10.0, 30.0]],
                pose: None,
            }),
            ..Project::default()
        };
        let solved = cage_coordinates(
            &project,
            CageMesh::Triangulate {
                target_vertices: 120,
            },
            &mut |_| true,
        )
        .expect("solved");
        let at_rest = warp_by_cage(&image, &solved).expect("warp");
        let shift: Vec<DVec2> = solved
            .pose
            .iter()
            .map(|p| *p + DVec2::new(5.0, 0.0))
            .collect();
        let moved = warp_by_cage_posed(&image, &solved, &shift).expect("warp");
        // Outside the rest cage and away from its moved copy: untouched.
        for (x, y) in [(2, 2), (55, 35), (5, 20)] {
            assert_eq!(moved.get_pixel(x, y), image.get_pixel(x, y));
        }
        // Inside: the picture shifted right by 5 pixels.
        assert_eq!(moved.get_pixel(30, 20), at_rest.get_pixel(25, 20));
        assert_ne!(moved.get_pixel(30, 20), image.get_pixel(30, 20));
    }
}
