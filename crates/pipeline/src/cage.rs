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
use project::{Canvas, MAX_CAGE_VERTICES, Method, Project, Tau};

use crate::Frame;

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

/// The most work a solve may take: mesh vertices inside the cage times cage vertices.
/// An ADMM iteration costs about that many operations, and a solve a few hundred
/// iterations: at this size it takes about a minute on a 2-core machine (92,000
/// vertices in a 16-vertex cage: 34 s). A larger request is refused, naming the limit.
pub const MAX_CAGE_WORK: usize = 3_000_000;

/// Mesh vertices inside a cage of `area` px² at most: as many per px² as a picture's
/// mesh may have ([`mesh::MAX_VERTICES_PER_PIXEL`]); more would only slice pixels.
pub fn cage_vertex_cap(area: f64) -> usize {
    (mesh::MAX_VERTICES_PER_PIXEL * area).ceil().max(1.0) as usize
}

/// Refuses a solve of `cage_vertices` with `mesh_vertices` inside that would take
/// more than about a minute.
fn check_work(mesh_vertices: usize, cage_vertices: usize) -> Result<()> {
    let work = mesh_vertices.saturating_mul(cage_vertices);
    ensure!(
        work <= MAX_CAGE_WORK,
        "a cage of {cage_vertices} vertices with {mesh_vertices} mesh vertices inside would \
         take minutes to solve: mesh vertices × cage vertices may be at most \
         {MAX_CAGE_WORK} (about a minute), here {work}; ask for at most {} mesh vertices \
         (--density or the rig's lbc.density) or use fewer cage vertices",
        MAX_CAGE_WORK / cage_vertices.max(1)
    );
    Ok(())
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
            let target = target_vertices.min(cage_vertex_cap(cage.area()));
            check_work(target, cage.len())?;
            lbc::Domain::triangulate(&cage, target).context("cannot triangulate the cage")?
        }
        CageMesh::Given {
            positions,
            triangles,
        } => {
            check_work(positions.len(), cage.len())?;
            lbc::Domain::from_mesh(&cage, positions, triangles)
                .context("the mesh does not fit the cage")?
        }
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
/// inside is composited over it). Drawn on the CPU at full resolution, 8 bits per
/// channel, in the picture's own frame or one grown to fit the warp (`canvas`).
///
/// # Errors
/// Non-finite deformed positions, or a picture (or grown canvas) too large to draw.
pub fn warp_by_cage(
    image: &image::RgbaImage,
    solved: &CageCoordinates,
    canvas: Canvas,
) -> Result<image::RgbaImage> {
    warp_by_cage_posed(image, solved, &solved.pose, canvas)
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
    canvas: Canvas,
) -> Result<image::RgbaImage> {
    let deformed = solved.weights.deform(pose)?;
    if deformed.iter().any(|p| !p.is_finite()) {
        bail!("the cage sent a vertex to a non-finite position");
    }
    let rest = rest_positions(solved);
    let deformed: Vec<glam::Vec2> = deformed.iter().map(|p| p.as_vec2()).collect();
    let (w, h) = image.dimensions();
    let frame = Frame::new(w, h, &deformed, canvas)?;
    let mut out = outside(image, solved, frame);
    render::warp_over(
        image,
        &render::WarpMesh {
            rest: &rest,
            deformed: &frame.place(&deformed),
            triangles: solved.domain.triangles(),
        },
        &mut out,
    )?;
    Ok(out)
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
    canvas: Canvas,
) -> Result<image::RgbaImage> {
    if solved.pose.iter().any(|p| !p.is_finite()) {
        bail!("the cage's pose is not finite");
    }
    let gpu = render::GpuContext::new()?;
    let rest = rest_positions(solved);
    let (rows, nodes, weights) = skinning_table(&solved.weights);
    let (w, h) = image.dimensions();
    let deformed: Vec<glam::Vec2> = solved.deformed()?.iter().map(|p| p.as_vec2()).collect();
    let frame = Frame::new(w, h, &deformed, canvas)?;
    let shift = frame.shift();
    let placed: Vec<DVec2> = solved.pose.iter().map(|p| *p + shift.as_dvec2()).collect();
    let layer = gpu.warp_skinned(
        image,
        &render::SkinnedMesh {
            rest: &rest,
            rows: &rows,
            nodes: &nodes,
            weights: &weights,
            triangles: solved.domain.triangles(),
        },
        &pose_transforms(&placed),
        frame.width,
        frame.height,
    )?;
    Ok(composite(&outside(image, solved, frame), &layer))
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

/// The picture outside the rest cage (its inside cleared), in `frame`: transparent
/// where the frame grows beyond the picture.
fn outside(image: &image::RgbaImage, solved: &CageCoordinates, frame: Frame) -> image::RgbaImage {
    let mut picture = image.clone();
    clear_inside(&mut picture, &solved.domain);
    if frame.origin == [0, 0] && (frame.width, frame.height) == image.dimensions() {
        return picture;
    }
    let mut out = image::RgbaImage::new(frame.width, frame.height);
    image::imageops::replace(&mut out, &picture, -frame.origin[0], -frame.origin[1]);
    out
}

/// `layer` (the warped inside, drawn on its own; transparent where it drew nothing)
/// over `base`.
fn composite(base: &image::RgbaImage, layer: &image::RgbaImage) -> image::RgbaImage {
    let mut out = base.clone();
    for (base, top) in out.pixels_mut().zip(layer.pixels()) {
        if top.0[3] > 0 {
            *base = render::over(top.0, base.0).into();
        }
    }
    out
}

/// Makes transparent every pixel the mesh of a cage's inside covers at rest, by the
/// rasteriser's own rule (pixel centres, top-left fill rule): the picture outside the
/// cage, as [`warp_by_cage`] keeps it. The warped inside is drawn over it, so at rest
/// every cleared pixel is drawn again from itself and the picture comes back exactly.
pub fn clear_inside(image: &mut image::RgbaImage, domain: &lbc::Domain) {
    let (w, h) = image.dimensions();
    let rest: Vec<glam::Vec2> = domain.positions().iter().map(|p| p.as_vec2()).collect();
    let mesh = render::WarpMesh {
        rest: &rest,
        deformed: &rest,
        triangles: domain.triangles(),
    };
    // The mesh comes from a validated cage, so it draws; if it did not, nothing is
    // cleared.
    let Ok(covered) = render::coverage_counts(&mesh, w, h) else {
        return;
    };
    for (pixel, &count) in image.pixels_mut().zip(&covered) {
        if count > 0 {
            *pixel = image::Rgba([0, 0, 0, 0]);
        }
    }
}

/// A cage around `image`'s visible shape (every pixel with alpha > 0, in every piece;
/// for an opaque picture, the picture's rectangle), as a user would click it:
/// `offset` pixels or more outside the shape, with `vertices` vertices.
///
/// The cage encloses every visible pixel whole ([`mesh::enclosing_ring`]: the alpha
/// mask dilated by `offset`, its pieces joined, its outline traced, then brought down
/// to `vertices` vertices by steps that only add area, the cheapest first, never
/// letting edges cross). Where `vertices` cannot enclose the shape without crossing,
/// the cage has more (compare its length with `vertices` to say so); a shape whose
/// outline has fewer gets its longest edges split. It lies within the picture.
///
/// # Errors
/// `vertices` outside 3 to [`MAX_CAGE_VERTICES`], a non-finite or negative `offset`,
/// or a picture without a visible pixel.
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
    let enclosure = match mesh::enclosing_ring(image, vertices, offset) {
        Err(mesh::MeshError::EmptyDomain) => {
            bail!("the picture has no visible pixel to put a cage around")
        }
        other => other?,
    };
    let mut ring = enclosure.ring;
    split_longest_edges(&mut ring, vertices);
    lbc::Cage::new(ring.clone()).context("the outline does not make a simple cage")?;
    Ok(ring)
}

/// How far outside a `width × height` picture's visible pixels a cage from its outline
/// runs by default: 1% of its diagonal, 3 to 20 pixels.
pub fn outline_offset(width: u32, height: u32) -> f64 {
    (0.01 * f64::from(width).hypot(f64::from(height))).clamp(3.0, 20.0)
}

/// What to tell a user who asked for a cage of `asked` vertices from the outline and
/// got `got`: nothing when they are the same.
pub fn outline_note(asked: usize, got: usize) -> Option<String> {
    (got > asked).then(|| {
        format!(
            "{asked} vertices cannot enclose the whole picture without the cage crossing \
             itself; it has {got}"
        )
    })
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

    /// The coordinates of the cage `rest` posed at `pose`, solved on `count` vertices.
    fn solved(rest: Vec<[f64; 2]>, pose: Option<Vec<[f64; 2]>>, count: usize) -> CageCoordinates {
        let project = Project {
            method: Method::Lbc,
            cage: Some(project::CageSpec { rest, pose }),
            ..Project::default()
        };
        cage_coordinates(
            &project,
            CageMesh::Triangulate {
                target_vertices: count,
            },
            &mut |_| true,
        )
        .expect("solved")
    }

    /// A 60 × 40 picture of colour ramps.
    fn ramps() -> image::RgbaImage {
        image::RgbaImage::from_fn(60, 40, |x, y| {
            image::Rgba([(x * 4) as u8, (y * 6) as u8, 90, 255])
        })
    }

    #[test]
    fn an_outline_cage_has_the_vertices_asked_for_and_encloses_the_whole_shape() {
        let image = cut_out();
        for n in [6, 16, 40] {
            let ring = cage_from_outline(&image, n, 6.0).expect("a cage");
            assert_eq!(ring.len(), n);
            assert_eq!(outline_note(n, ring.len()), None);
            let cage = lbc::Cage::new(ring.clone()).expect("simple");
            // Outside the shape: no vertex on a visible pixel.
            for p in &ring {
                let (x, y) = (p.x.floor() as u32, p.y.floor() as u32);
                if x < 200 && y < 160 {
                    assert_eq!(image.get_pixel(x, y).0[3], 0, "vertex {p} on the shape");
                }
            }
            for (x, y, px) in image.enumerate_pixels() {
                if px.0[3] > 0 {
                    let c = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                    assert!(cage.contains(c), "{n} vertices leave ({x}, {y}) out");
                }
            }
        }
        assert!(outline_note(8, 9).is_some_and(|m| m.contains("has 9")));
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
    fn a_cage_at_rest_gives_the_picture_back_exactly() {
        // Every kind of pixel (opaque, half-covered, transparent), and cages inside
        // the picture, on its border (edges through pixel edges and corners) and
        // around a concave notch, each at a density where many weights are dropped.
        let image = image::RgbaImage::from_fn(90, 70, |x, y| {
            let a = [255, 128, 0, 37][((x / 3 + y / 5) % 4) as usize];
            image::Rgba([(x * 3) as u8, (y * 3) as u8, ((x * y) % 256) as u8, a])
        });
        let cages = [
            vec![[10.5, 8.25], [61.0, 12.0], [70.0, 50.5], [20.0, 60.0]],
            vec![[0.0, 0.0], [90.0, 0.0], [90.0, 70.0], [0.0, 70.0]],
            vec![
                [0.0, 0.0],
                [90.0, 0.0],
                [90.0, 70.0],
                [60.0, 70.0],
                [45.0, 20.0],
                [30.0, 70.0],
                [0.0, 70.0],
            ],
        ];
        for rest in cages {
            let solved = solved(rest, None, 400);
            let at_rest = warp_by_cage(&image, &solved, Canvas::Keep).expect("warp");
            let changed = at_rest
                .pixels()
                .zip(image.pixels())
                .filter(|(a, b)| a != b)
                .count();

            assert_eq!(changed, 0, "{:?}", solved.domain.cage().vertices());
        }
    }

    #[test]
    fn a_grown_canvas_holds_what_the_cage_takes_beyond_the_picture() {
        let image = ramps();
        let square = vec![[10.0, 10.0], [40.0, 10.0], [40.0, 30.0], [10.0, 30.0]];
        let moved = vec![[40.0, -5.0], [70.0, -5.0], [70.0, 15.0], [40.0, 15.0]];
        let solved = solved(square, Some(moved), 120);
        let kept = warp_by_cage(&image, &solved, Canvas::Keep).expect("warp");
        let grown = warp_by_cage(&image, &solved, Canvas::Fit).expect("warp");
        assert_eq!(kept.dimensions(), (60, 40));
        // Moved 30 right and 15 up: the canvas grows to x ∈ [0, 70], y ∈ [−5, 40].
        assert_eq!(grown.dimensions(), (70, 45));
        // The picture's frame sits 5 px down in it, as kept.
        let frame = image::imageops::crop_imm(&grown, 0, 5, 60, 40).to_image();
        assert_eq!(frame, kept);
        // Beyond the picture's right edge: the cage's inside, not nothing.
        assert_eq!(grown.get_pixel(65, 10).0[3], 255);
        assert_eq!(grown.get_pixel(65, 30).0[3], 0);
    }

    #[test]
    fn a_posed_warp_moves_the_inside_and_keeps_the_outside() {
        let image = ramps();
        let square = vec![[10.0, 10.0], [40.0, 10.0], [40.0, 30.0], [10.0, 30.0]];
        let solved = solved(square, None, 120);
        let at_rest = warp_by_cage(&image, &solved, Canvas::Keep).expect("warp");
        let shift: Vec<DVec2> = solved
            .pose
            .iter()
            .map(|p| *p + DVec2::new(5.0, 0.0))
            .collect();
        let moved = warp_by_cage_posed(&image, &solved, &shift, Canvas::Keep).expect("warp");
        // Outside the rest cage and away from its moved copy: untouched.
        for (x, y) in [(2, 2), (55, 35), (5, 20)] {
            assert_eq!(moved.get_pixel(x, y), image.get_pixel(x, y));
        }
        // Inside: the picture shifted right by 5 pixels.
        assert_eq!(moved.get_pixel(30, 20), at_rest.get_pixel(25, 20));
        assert_ne!(moved.get_pixel(30, 20), image.get_pixel(30, 20));
    }
}
