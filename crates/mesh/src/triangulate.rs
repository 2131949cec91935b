//! Constrained Delaunay triangulation of a domain with spade, seeded on a hexagonal
//! lattice and lightly refined.

use std::collections::HashMap;
use std::panic::{AssertUnwindSafe, catch_unwind};

use geometry::{orient, point_segment_distance_squared, signed_area};
use glam::DVec2;
use spade::handles::{FixedVertexHandle, VertexHandle};
use spade::{
    AngleLimit, CdtEdge, ConstrainedDelaunayTriangulation, Point2, RefinementParameters,
    Triangulation,
};

use crate::segments::{RingBands, SegmentGrid, exactly_collinear, lerp, segment_hits};
use crate::{Domain, DomainOptions, Mesh, MeshError, domain_for_density};

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// Most vertices per px² of domain that [`triangulate`] will aim for.
pub const MAX_VERTICES_PER_PIXEL: f64 = 4.0;

/// Lattice points closer than this many lattice spacings to the boundary, a constraint
/// point or a polyline are left out, so no sliver triangles form there.
const CLEARANCE: f64 = 0.5;

/// Mesh density and quality.
#[derive(Debug, Clone)]
pub struct MeshOptions {
    /// About how many vertices the mesh should have (the result lands within about
    /// ±30%, usually much closer). Default 20 000. Capped at
    /// [`MAX_VERTICES_PER_PIXEL`] per px² of domain; at least the boundary's and the
    /// constraints' vertices are always used.
    pub target_vertices: usize,
    /// Smallest triangle angle (degrees) the refinement aims for, except next to small
    /// angles of the input (sharp outline corners, constraints close to each other).
    /// Clamped to `[0, 33]`; NaN means the default. Default 25.
    pub min_angle_deg: f64,
    /// Points where the mesh is refined locally (the picture's handles that sit closer
    /// together than its spacing, with rings around them): each becomes a vertex at
    /// exactly its coordinates, and the lattice keeps clear of it, as a constraint point
    /// does; one off the domain is left out. They play no part in the lattice's
    /// spacing, so every lattice point away from them is where it is without them.
    /// Default none.
    pub refine: Vec<DVec2>,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions {
            target_vertices: 20_000,
            min_angle_deg: 25.0,
            refine: Vec::new(),
        }
    }
}

/// Points and polylines that must appear in the mesh, in pixel coordinates.
#[derive(Debug, Clone, Copy, Default)]
pub struct Constraints<'a> {
    /// Each becomes a mesh vertex at exactly these coordinates (e.g. point handles).
    pub points: &'a [DVec2],
    /// Each point becomes a vertex at exactly its coordinates, and each pair of
    /// consecutive points is joined by a chain of collinear mesh edges (e.g. bar
    /// handles). Polylines may cross each other (a vertex is added at the crossing) but
    /// not leave the domain.
    pub polylines: &'a [Vec<DVec2>],
}

/// A triangulated domain and where the constraints ended up.
#[derive(Debug, Clone)]
pub struct TriangulatedImage {
    /// The mesh; see [`Mesh`] for its orientation.
    pub mesh: Mesh,
    /// Vertex index of each [`Constraints::points`] entry (equal points share a vertex).
    pub point_vertices: Vec<u32>,
    /// Vertex index of each point of each [`Constraints::polylines`] entry.
    pub polyline_vertices: Vec<Vec<u32>>,
    /// For each polyline, every vertex along it in order, from its first point to its
    /// last: its own points and the extra vertices that split its segments. Consecutive
    /// entries are joined by mesh edges.
    pub polyline_paths: Vec<Vec<u32>>,
    /// `true` when the domain is the full image rectangle (convex).
    pub is_convex: bool,
}

/// Meshes an image in one call: [`domain_for_density`] at
/// [`MeshOptions::target_vertices`], then [`triangulate`].
///
/// # Errors
/// As [`domain_for_density`] and [`triangulate`].
///
/// # Example
/// ```
/// use glam::DVec2;
/// use mesh::{Constraints, DomainOptions, MeshOptions, mesh_image};
///
/// let img = image::RgbaImage::from_pixel(64, 48, image::Rgba([9, 9, 9, 255]));
/// let handles = [DVec2::new(10.5, 20.25), DVec2::new(40.0, 30.0)];
/// let opts = MeshOptions { target_vertices: 500, ..MeshOptions::default() };
/// let constraints = Constraints { points: &handles, polylines: &[] };
/// let t = mesh_image(&img, &DomainOptions::default(), &opts, &constraints)?;
/// assert!(t.is_convex);
/// assert_eq!(t.mesh.vertices[t.point_vertices[0] as usize], handles[0]);
/// assert!((t.mesh.area() - 64.0 * 48.0).abs() < 1e-6);
/// t.mesh.sanity_check()?;
/// # Ok::<(), mesh::MeshError>(())
/// ```
pub fn mesh_image(
    image: &image::RgbaImage,
    domain_opts: &DomainOptions,
    opts: &MeshOptions,
    constraints: &Constraints,
) -> Result<TriangulatedImage, MeshError> {
    let domain = domain_for_density(image, domain_opts, opts.target_vertices)?;
    triangulate(&domain, constraints, opts)
}

/// Triangulates a domain: a constrained Delaunay triangulation (spade) whose constraint
/// edges are the domain's rings and the constraint polylines, keeping only triangles
/// inside the domain.
///
/// Method:
/// 1. Interior vertices are seeded on a hexagonal lattice whose spacing gives about
///    [`MeshOptions::target_vertices`] vertices (calibrated once for the vertices the
///    boundary and constraints take), leaving a gap of half a spacing around the
///    boundary and the constraints. Ring and polyline segments are split to the same
///    spacing (ring split points only where they fall exactly on the segment).
/// 2. Everything is bulk-loaded into a spade CDT, inside a frame unless the domain is an
///    axis-aligned convex polygon (the image rectangle), so no ring edge lies on the
///    convex hull.
/// 3. Spade's Delaunay refinement fixes triangles below the angle limit or above twice
///    the lattice triangle area, ignoring faces outside the domain. This is light: it
///    typically adds a few percent of the vertices, near the boundary.
/// 4. Triangles are kept by parity of crossed ring edges (so closed constraint polylines
///    do not carve holes; their inside is seeded but not refined), and the vertices in
///    use are numbered along a Z-order curve of their positions, so that mesh
///    neighbours are mostly near in memory (graph searches over the mesh run from
///    cache; on the lizard at 100k vertices this made insertions 40% faster).
///
/// Constraint vertices are never moved or removed. A constraint point on the boundary
/// (within 1e-9 px, relative to the coordinate magnitude) is made a ring vertex, so the
/// boundary passes exactly through it. Every returned vertex is used by a triangle,
/// triangles are non-degenerate and follow [`Mesh`]'s orientation.
///
/// # Errors
/// * [`MeshError::EmptyDomain`]: no polygon, or zero total area.
/// * [`MeshError::InvalidDomain`]: a ring with fewer than 3 vertices or zero area, or
///   rings that cross.
/// * [`MeshError::NonFinite`]: a NaN or infinite coordinate.
/// * [`MeshError::CoordinateOutOfRange`]: a coordinate above 1e50 or below 1e-40 in
///   magnitude (but not zero).
/// * [`MeshError::PointOutsideDomain`], [`MeshError::PolylinePointOutsideDomain`],
///   [`MeshError::PolylineOutsideDomain`]: a constraint off the shape.
/// * [`MeshError::Triangulation`]: an internal failure of the triangulator.
pub fn triangulate(
    domain: &Domain,
    constraints: &Constraints,
    opts: &MeshOptions,
) -> Result<TriangulatedImage, MeshError> {
    // --- Validate the domain -------------------------------------------------------
    if domain.polygons.is_empty() {
        return Err(MeshError::EmptyDomain);
    }
    let mut extent = 0.0f64;
    for (pi, poly) in domain.polygons.iter().enumerate() {
        for (ri, ring) in poly.rings().enumerate() {
            let name = || {
                if ri == 0 {
                    format!("outer ring of polygon {pi}")
                } else {
                    format!("hole {} of polygon {pi}", ri - 1)
                }
            };
            for &p in ring {
                check_coords(p, name)?;
            }
            if ring.len() < 3 {
                return Err(MeshError::InvalidDomain(format!(
                    "{} has {} vertices, needs at least 3",
                    name(),
                    ring.len()
                )));
            }
            if signed_area(ring) == 0.0 {
                return Err(MeshError::InvalidDomain(format!(
                    "{} has zero area",
                    name()
                )));
            }
            for p in ring {
                extent = extent.max(p.abs().max_element());
            }
        }
    }
    let area = domain.area();
    if area.is_nan() || area <= 0.0 {
        return Err(MeshError::EmptyDomain);
    }

    // --- Lattice spacing ----------------------------------------------------------
    let target = (opts.target_vertices as f64)
        .min(MAX_VERTICES_PER_PIXEL * area)
        .max(1.0);
    let spacing = |n: f64| (2.0 * area / (3f64.sqrt() * n)).sqrt();
    let mut s = spacing(target);
    let min_angle = if opts.min_angle_deg.is_nan() {
        MeshOptions::default().min_angle_deg
    } else {
        opts.min_angle_deg.clamp(0.0, 33.0)
    };

    let bands = RingBands::new(domain.rings(), (s * 0.866).max(extent * 1e-9));

    // --- Validate constraints -----------------------------------------------------
    for (i, p) in constraints.points.iter().enumerate() {
        check_coords(*p, || format!("constraint point {i}"))?;
        if !bands.contains(*p) {
            return Err(MeshError::PointOutsideDomain {
                index: i,
                x: p.x,
                y: p.y,
            });
        }
    }
    let ring_segs: Vec<[DVec2; 2]> = domain
        .rings()
        .flat_map(|r| (0..r.len()).map(move |i| [r[i], r[(i + 1) % r.len()]]))
        .filter(|s| s[0] != s[1])
        .collect();
    for (k, line) in constraints.polylines.iter().enumerate() {
        for (i, p) in line.iter().enumerate() {
            check_coords(*p, || format!("point {i} of polyline {k}"))?;
            if !bands.contains(*p) {
                return Err(MeshError::PolylinePointOutsideDomain {
                    polyline: k,
                    index: i,
                    x: p.x,
                    y: p.y,
                });
            }
        }
        let mut ts = Vec::new();
        for (i, w) in line.windows(2).enumerate() {
            let (p, q) = (w[0], w[1]);
            ts.clear();
            ts.extend([0.0, 1.0]);
            for seg in &ring_segs {
                segment_hits(p, q, seg[0], seg[1], &mut ts);
            }
            ts.sort_by(f64::total_cmp);
            for t in ts.windows(2) {
                if t[1] - t[0] > 1e-9 && !bands.contains(lerp(p, q, 0.5 * (t[0] + t[1]))) {
                    return Err(MeshError::PolylineOutsideDomain {
                        polyline: k,
                        segment: i,
                    });
                }
            }
        }
    }

    // --- Seed vertices, calibrating the spacing once -------------------------------
    let mut seeds = Seeds::build(domain, constraints, &[], &bands, s, extent);
    let n0 = seeds.vertices.len() as f64;
    let mut bands = bands;
    let calibrate =
        opts.target_vertices > 0 && (n0 / target - 1.0).abs() > 0.03 && seeds.lattice_count > 0;
    if calibrate {
        // The boundary and constraints take vertices too; shrink or grow the lattice.
        let fixed = (seeds.vertices.len() - seeds.lattice_count) as f64;
        let want_lattice = (target - fixed).max(0.25 * target);
        let ratio = seeds.lattice_count as f64 / want_lattice;
        s *= ratio.sqrt().clamp(0.5, 2.0);
        bands = RingBands::new(domain.rings(), (s * 0.866).max(extent * 1e-9));
    }
    // The refinement points inside the domain, finite ones only; seeded after the
    // calibration, which they take no part in.
    let refine: Vec<DVec2> = opts
        .refine
        .iter()
        .copied()
        .filter(|p| {
            // One on the boundary itself would sit on a constraint edge: left out.
            p.is_finite() && bands.contains(*p) && !bands.near_boundary(*p, 1e-9 * (1.0 + extent))
        })
        .collect();
    if calibrate || !refine.is_empty() {
        seeds = Seeds::build(domain, constraints, &refine, &bands, s, extent);
    }

    // --- Triangulate (spade), guarding against panics in the triangulator ---------
    let lattice_area = 3f64.sqrt() / 4.0 * s * s;
    let max_extra = (target as usize).max(1000).max(seeds.vertices.len());
    let result = catch_unwind(AssertUnwindSafe(|| {
        build_mesh(
            domain,
            &seeds,
            &ring_segs,
            extent,
            lattice_area,
            min_angle,
            max_extra,
        )
    }));
    let built = match result {
        Ok(r) => r?,
        Err(payload) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic in the triangulator".into());
            return Err(MeshError::Triangulation(msg));
        }
    };

    // --- Map constraint vertices to mesh indices -----------------------------------
    let map = |seed: u32| {
        built
            .new_index
            .get(seed as usize)
            .copied()
            .unwrap_or(u32::MAX)
    };
    let mut point_vertices = Vec::with_capacity(constraints.points.len());
    for (i, &seed) in seeds.point_ids.iter().enumerate() {
        let v = map(seed);
        if v == u32::MAX {
            let p = constraints.points[i];
            return Err(MeshError::PointOutsideDomain {
                index: i,
                x: p.x,
                y: p.y,
            });
        }
        point_vertices.push(v);
    }
    let mut polyline_vertices = Vec::with_capacity(constraints.polylines.len());
    for (k, ids) in seeds.polyline_ids.iter().enumerate() {
        let mut out = Vec::with_capacity(ids.len());
        for (i, &seed) in ids.iter().enumerate() {
            let v = map(seed);
            if v == u32::MAX {
                let p = constraints.polylines[k][i];
                return Err(MeshError::PolylinePointOutsideDomain {
                    polyline: k,
                    index: i,
                    x: p.x,
                    y: p.y,
                });
            }
            out.push(v);
        }
        polyline_vertices.push(out);
    }
    let mut polyline_paths = Vec::with_capacity(built.paths.len());
    for (k, path) in built.paths.iter().enumerate() {
        let mut out = Vec::with_capacity(path.len());
        for &h in path {
            let v = built.new_index.get(h).copied().unwrap_or(u32::MAX);
            if v == u32::MAX {
                return Err(MeshError::PolylineOutsideDomain {
                    polyline: k,
                    segment: 0,
                });
            }
            out.push(v);
        }
        polyline_paths.push(out);
    }
    Ok(TriangulatedImage {
        mesh: built.mesh,
        point_vertices,
        polyline_vertices,
        polyline_paths,
        is_convex: domain.is_full_rectangle,
    })
}

/// Smallest non-zero coordinate magnitude accepted (spade rejects subnormal-range values).
const MIN_COORDINATE: f64 = 1e-40;
/// Largest coordinate magnitude accepted.
const MAX_COORDINATE: f64 = 1e50;

/// Checks that a coordinate pair is finite and in the range the triangulator handles.
fn check_coords(p: DVec2, what: impl Fn() -> String) -> Result<(), MeshError> {
    if !p.is_finite() {
        return Err(MeshError::NonFinite { what: what() });
    }
    let ok = |v: f64| v == 0.0 || (MIN_COORDINATE..=MAX_COORDINATE).contains(&v.abs());
    if ok(p.x) && ok(p.y) {
        Ok(())
    } else {
        Err(MeshError::CoordinateOutOfRange { what: what() })
    }
}

/// The vertices and constraint edges handed to spade.
struct Seeds {
    vertices: Vec<Point2<f64>>,
    /// Boundary edges (indices into `vertices`).
    boundary_edges: Vec<[usize; 2]>,
    /// Polyline sub-edges.
    polyline_edges: Vec<[usize; 2]>,
    /// Seed index of each constraint point.
    point_ids: Vec<u32>,
    /// Seed index of each polyline point.
    polyline_ids: Vec<Vec<u32>>,
    /// How many of `vertices` (at the end) are lattice points.
    lattice_count: usize,
}

impl Seeds {
    fn build(
        domain: &Domain,
        constraints: &Constraints,
        refine: &[DVec2],
        bands: &RingBands,
        s: f64,
        extent: f64,
    ) -> Seeds {
        let mut seeds = Seeds {
            vertices: Vec::new(),
            boundary_edges: Vec::new(),
            polyline_edges: Vec::new(),
            point_ids: Vec::new(),
            polyline_ids: Vec::new(),
            lattice_count: 0,
        };
        let mut index: HashMap<[u64; 2], u32> = HashMap::new();
        let mut add = |verts: &mut Vec<Point2<f64>>, p: DVec2| -> u32 {
            // `+ 0.0` turns -0.0 into 0.0 so both hash alike.
            let key = [(p.x + 0.0).to_bits(), (p.y + 0.0).to_bits()];
            *index.entry(key).or_insert_with(|| {
                verts.push(Point2::new(p.x + 0.0, p.y + 0.0));
                (verts.len() - 1) as u32
            })
        };
        let pieces = |len: f64| ((len / s).ceil().clamp(1.0, 1e7)) as usize;

        // Polylines split to the lattice spacing: (position, index of the polyline point
        // it is, if any).
        let samples: Vec<Vec<(DVec2, Option<usize>)>> = constraints
            .polylines
            .iter()
            .map(|line| {
                let mut out = Vec::new();
                for (i, &p) in line.iter().enumerate() {
                    if i > 0 {
                        let a = line[i - 1];
                        let m = pieces(a.distance(p));
                        for j in 1..m {
                            out.push((lerp(a, p, j as f64 / m as f64), None));
                        }
                    }
                    out.push((p, Some(i)));
                }
                out
            })
            .collect();

        // Constraint vertices on (or within a hair of) the boundary become ring vertices,
        // so the boundary passes exactly through them.
        let tol = 1e-9 * (1.0 + extent);
        let on_boundary: Vec<DVec2> = constraints
            .points
            .iter()
            .copied()
            .chain(samples.iter().flatten().map(|&(p, _)| p))
            .filter(|&p| bands.near_boundary(p, tol))
            .collect();
        // Pieces that lattice points keep clear of.
        let mut clear: Vec<[DVec2; 2]> = Vec::new();
        let mut splits: Vec<(f64, DVec2)> = Vec::new();
        // Ring segments that hold constraint vertices.
        let mut busy_segments: Vec<[DVec2; 2]> = Vec::new();
        for ring in domain.rings() {
            let n = ring.len();
            let mut ids: Vec<u32> = Vec::new();
            for i in 0..n {
                let (a, b) = (ring[i], ring[(i + 1) % n]);
                let len2 = a.distance_squared(b);
                if len2 == 0.0 {
                    continue;
                }
                splits.clear();
                for &p in &on_boundary {
                    if point_segment_distance_squared(p, a, b) <= tol * tol {
                        if p != a && p != b {
                            splits.push(((p - a).dot(b - a) / len2, p));
                        }
                        if busy_segments.last() != Some(&[a, b]) {
                            busy_segments.push([a, b]);
                        }
                    }
                }
                // Regular split points, except those crowding a constraint vertex. Only
                // points exactly on the segment are used: one rounded off the line would
                // leave a sliver outside a convex-hull edge. A power-of-two count makes
                // them exact for integer (traced) coordinates; spade's refinement splits
                // whatever is left too long.
                let m = pieces(len2.sqrt());
                let exact = |m: usize| {
                    (1..m).all(|j| exactly_collinear(a, b, lerp(a, b, j as f64 / m as f64)))
                };
                let m = if exact(m) { m } else { m.next_power_of_two() };
                let step = 1.0 / m as f64;
                for j in 0..m {
                    let t = j as f64 * step;
                    let p = lerp(a, b, t);
                    if j == 0
                        || (splits.iter().all(|&(u, _)| (u - t).abs() > 0.3 * step)
                            && exactly_collinear(a, b, p))
                    {
                        splits.push((t, p));
                    }
                }
                splits.sort_by(|x, y| x.0.total_cmp(&y.0));
                let mut prev = a;
                for &(_, p) in splits.iter() {
                    ids.push(add(&mut seeds.vertices, p));
                    clear.push([prev, p]);
                    prev = p;
                }
                clear.push([prev, b]);
            }
            for i in 0..ids.len() {
                let (a, b) = (ids[i], ids[(i + 1) % ids.len()]);
                if a != b {
                    seeds.boundary_edges.push([a as usize, b as usize]);
                }
            }
        }
        let on_same_segment = |p: DVec2, q: DVec2| {
            busy_segments.iter().any(|&[a, b]| {
                point_segment_distance_squared(p, a, b) <= tol * tol
                    && point_segment_distance_squared(q, a, b) <= tol * tol
            })
        };

        for &p in constraints.points {
            seeds.point_ids.push(add(&mut seeds.vertices, p));
            clear.push([p, p]);
        }
        for &p in refine {
            add(&mut seeds.vertices, p);
            clear.push([p, p]);
        }
        for (line, samples) in constraints.polylines.iter().zip(&samples) {
            let mut ids = vec![0u32; line.len()];
            let mut prev: Option<(u32, DVec2)> = None;
            for &(p, own) in samples {
                let id = add(&mut seeds.vertices, p);
                if let Some(i) = own {
                    ids[i] = id;
                }
                match prev {
                    Some((q, pq)) => {
                        // Sub-edges lying on the boundary are constraint edges already.
                        if q != id && !on_same_segment(pq, p) {
                            seeds.polyline_edges.push([q as usize, id as usize]);
                        }
                        clear.push([pq, p]);
                    }
                    None => clear.push([p, p]),
                }
                prev = Some((id, p));
            }
            seeds.polyline_ids.push(ids);
        }

        // Hexagonal lattice, row by row, inside the domain and clear of the pieces.
        let grid = SegmentGrid::new(clear, s);
        let (lo, hi) = domain.rings().flatten().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let row_h = s * 3f64.sqrt() / 2.0;
        let rows = ((hi.y - lo.y) / row_h).floor();
        let before = seeds.vertices.len();
        if rows.is_finite() && rows < 1e7 {
            let mut xs = Vec::new();
            for j in 0..=(rows as usize) {
                let y = lo.y + (j as f64 + 0.5) * row_h;
                if y >= hi.y {
                    break;
                }
                bands.crossings(y, &mut xs);
                let off = lo.x + if j % 2 == 1 { 0.75 * s } else { 0.25 * s };
                for pair in xs.chunks_exact(2) {
                    let (xa, xb) = (pair[0], pair[1]);
                    let k0 = ((xa - off) / s).ceil();
                    let k1 = ((xb - off) / s).floor();
                    if k0.is_nan() || k1.is_nan() || k0 > k1 {
                        continue;
                    }
                    for k in (k0 as i64)..=(k1 as i64) {
                        let p = DVec2::new(off + k as f64 * s, y);
                        if p.x > xa && p.x < xb && !grid.any_within(p, CLEARANCE * s) {
                            seeds.vertices.push(Point2::new(p.x, p.y));
                        }
                    }
                }
            }
        }
        seeds.lattice_count = seeds.vertices.len() - before;
        seeds
    }
}

struct Built {
    mesh: Mesh,
    /// New mesh index of each spade vertex (`u32::MAX` when unused).
    new_index: Vec<u32>,
    /// Spade vertex indices along each polyline.
    paths: Vec<Vec<usize>>,
}

fn pos(v: VertexHandle<'_, Point2<f64>, (), CdtEdge<()>, ()>) -> DVec2 {
    let p = v.position();
    DVec2::new(p.x, p.y)
}

fn build_mesh(
    domain: &Domain,
    seeds: &Seeds,
    ring_segs: &[[DVec2; 2]],
    extent: f64,
    lattice_area: f64,
    min_angle: f64,
    max_extra: usize,
) -> Result<Built, MeshError> {
    // Unless the domain is an axis-aligned convex polygon (the image rectangle), put a
    // frame around it, so that no domain edge is on the convex hull. Refinement splits
    // hull edges at points rounded off the line, which can leave sliver triangles outside
    // a slanted hull edge that then get refined over and over.
    let simple_rectangle = matches!(domain.polygons.as_slice(),
        [p] if p.holes.is_empty() && is_convex(&p.outer) && is_axis_aligned(&p.outer));
    let mut vertices = seeds.vertices.clone();
    if !simple_rectangle {
        let (lo, hi) = vertices.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(DVec2::new(p.x, p.y)), hi.max(DVec2::new(p.x, p.y))),
        );
        let margin = 0.25 * (hi - lo).max_element() + 1.0;
        let (lo, hi) = (lo - margin, hi + margin);
        for p in [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)] {
            vertices.push(Point2::new(p.x, p.y));
        }
    }
    let mut conflicts = Vec::new();
    let mut cdt = Cdt::try_bulk_load_cdt(vertices.clone(), seeds.boundary_edges.clone(), |e| {
        conflicts.push(e)
    })
    .map_err(|e| MeshError::Triangulation(format!("{e:?}")))?;
    if let Some([a, _]) = conflicts.first() {
        let p = seeds.vertices[*a];
        return Err(MeshError::InvalidDomain(format!(
            "domain rings cross each other near ({}, {})",
            p.x, p.y
        )));
    }
    if cdt.num_vertices() != vertices.len() {
        return Err(MeshError::Triangulation(
            "vertices were merged unexpectedly".into(),
        ));
    }
    for &[a, b] in &seeds.polyline_edges {
        cdt.add_constraint_and_split(
            FixedVertexHandle::from_index(a),
            FixedVertexHandle::from_index(b),
            |p| p,
        );
    }

    let mut params = RefinementParameters::<f64>::new()
        .exclude_outer_faces(!simple_rectangle)
        .with_angle_limit(AngleLimit::from_deg(min_angle))
        .with_max_additional_vertices(max_extra);
    if lattice_area.is_finite() && lattice_area > 0.0 {
        params = params
            .with_max_allowed_area(2.0 * lattice_area)
            .with_min_required_area(1e-3 * lattice_area);
    }
    cdt.refine(params);

    // --- Inside/outside: parity of crossed boundary edges -------------------------
    let tol = 1e-9 * (1.0 + extent);
    let boundary_grid = SegmentGrid::new(ring_segs.to_vec(), (extent / 256.0).max(1e-6));
    let is_boundary = |a: DVec2, b: DVec2| -> bool {
        let m = 0.5 * (a + b);
        let t2 = tol * tol;
        boundary_grid.any_near(m, tol, |i| {
            let [p, q] = boundary_grid.segments()[i];
            point_segment_distance_squared(m, p, q) <= t2
                && point_segment_distance_squared(a, p, q) <= t2
                && point_segment_distance_squared(b, p, q) <= t2
        })
    };
    const UNSEEN: u8 = 0;
    const OUT: u8 = 1;
    const IN: u8 = 2;
    let mut state = vec![UNSEEN; cdt.num_all_faces()];
    let mut stack = Vec::new();
    for e in cdt.directed_edges() {
        if !e.face().is_outer() {
            continue;
        }
        let Some(inner) = e.rev().face().as_inner() else {
            continue;
        };
        let idx = inner.fix().index();
        if state[idx] != UNSEEN {
            continue;
        }
        let crossing = e.is_constraint_edge() && is_boundary(pos(e.from()), pos(e.to()));
        state[idx] = if crossing { IN } else { OUT };
        stack.push(inner.fix());
    }
    while let Some(f) = stack.pop() {
        let st = state[f.index()];
        for e in cdt.face(f).adjacent_edges() {
            let Some(g) = e.rev().face().as_inner() else {
                continue;
            };
            let gi = g.fix().index();
            if state[gi] != UNSEEN {
                continue;
            }
            let crossing = e.is_constraint_edge() && is_boundary(pos(e.from()), pos(e.to()));
            state[gi] = if crossing {
                if st == IN { OUT } else { IN }
            } else {
                st
            };
            stack.push(g.fix());
        }
    }

    // --- Polyline paths, in spade indices ------------------------------------------
    let mut paths = Vec::with_capacity(seeds.polyline_ids.len());
    for ids in &seeds.polyline_ids {
        let mut path: Vec<usize> = Vec::new();
        if let Some(&first) = ids.first() {
            path.push(first as usize);
        }
        for w in ids.windows(2) {
            if w[0] == w[1] {
                continue;
            }
            let chain = walk_constraint(&cdt, w[0] as usize, w[1] as usize).ok_or_else(|| {
                MeshError::Triangulation("lost a polyline edge during refinement".into())
            })?;
            path.extend(chain.into_iter().skip(1));
        }
        paths.push(path);
    }

    // --- Extract the inside triangles ------------------------------------------------
    let mut new_index = vec![u32::MAX; cdt.num_vertices()];
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for face in cdt.inner_faces() {
        if state[face.fix().index()] != IN {
            continue;
        }
        let tri = face.vertices().map(|v| {
            let i = v.fix().index();
            if new_index[i] == u32::MAX {
                new_index[i] = vertices.len() as u32;
                vertices.push(pos(v));
            }
            new_index[i]
        });
        triangles.push(tri);
    }
    if triangles.is_empty() {
        return Err(MeshError::EmptyDomain);
    }
    // Vertices in Z order (by position), so that mesh neighbours are mostly near in
    // memory too: graph searches over the mesh then run from cache.
    let order = geometry::z_order(&vertices);
    let mut rank = vec![0u32; vertices.len()];
    for (r, &v) in order.iter().enumerate() {
        rank[v as usize] = r as u32;
    }
    let vertices = order.iter().map(|&v| vertices[v as usize]).collect();
    for t in &mut triangles {
        for v in t.iter_mut() {
            *v = rank[*v as usize];
        }
    }
    for i in new_index.iter_mut().filter(|i| **i != u32::MAX) {
        *i = rank[*i as usize];
    }
    Ok(Built {
        mesh: Mesh {
            vertices,
            triangles,
        },
        new_index,
        paths,
    })
}

/// Whether a ring is convex (collinear vertices allowed).
fn is_convex(ring: &[DVec2]) -> bool {
    let n = ring.len();
    let (mut pos, mut neg) = (false, false);
    for i in 0..n {
        let o = orient(ring[i], ring[(i + 1) % n], ring[(i + 2) % n]);
        pos |= o > 0.0;
        neg |= o < 0.0;
    }
    !(pos && neg)
}

/// Whether every edge of a ring is horizontal or vertical.
fn is_axis_aligned(ring: &[DVec2]) -> bool {
    let n = ring.len();
    (0..n).all(|i| {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        a.x == b.x || a.y == b.y
    })
}

/// Follows constraint edges from vertex `from` straight towards vertex `to`.
fn walk_constraint(cdt: &Cdt, from: usize, to: usize) -> Option<Vec<usize>> {
    let a = pos(cdt.vertex(FixedVertexHandle::from_index(from)));
    let b = pos(cdt.vertex(FixedVertexHandle::from_index(to)));
    let len = a.distance(b);
    let dir = (b - a) / len;
    let mut path = vec![from];
    let mut cur = from;
    for _ in 0..cdt.num_vertices() {
        if cur == to {
            return Some(path);
        }
        let v = cdt.vertex(FixedVertexHandle::from_index(cur));
        let here = pos(v);
        let mut best = None;
        let mut best_cos = 1.0 - 1e-9;
        for e in v.out_edges() {
            if !e.is_constraint_edge() {
                continue;
            }
            let t = e.to();
            let d = pos(t) - here;
            let cos = d.dot(dir) / d.length();
            if cos > best_cos && (pos(t) - a).dot(dir) <= len * (1.0 + 1e-9) {
                best_cos = cos;
                best = Some(t.fix().index());
            }
        }
        cur = best?;
        path.push(cur);
    }
    None
}
