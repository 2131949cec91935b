//! How ARAP pins hold and pull at the product's densities: a picture with pins fixed at
//! rest and one moved, measured where an artist looks (around the pins) and compared
//! between densities. Shared by `tests/arap_pins.rs` and `examples/arap_pins.rs`.

#![allow(dead_code)]

use super::figure;

use glam::DVec2;
use image::{Rgba, RgbaImage};
use project::{HandleSpec, Method, Project};

/// A picture with pins: some fixed at rest, one moved.
pub struct PinCase {
    /// What it is, for messages.
    pub name: &'static str,
    /// The picture.
    pub image: RgbaImage,
    /// Pins held at rest.
    pub fixed: Vec<DVec2>,
    /// The pin that moves, and by how much.
    pub moved: DVec2,
    /// Its displacement.
    pub by: DVec2,
}

impl PinCase {
    /// The picture's diagonal in pixels.
    pub fn diagonal(&self) -> f64 {
        f64::from(self.image.width()).hypot(f64::from(self.image.height()))
    }

    /// The rig: ARAP, the fixed pins then the moved one, `arap` as the rig file's ARAP
    /// settings (JSON, e.g. `{"pin_radius": 0}`; `None` for the defaults).
    pub fn project(&self, arap: Option<&str>) -> Project {
        let point = |p: DVec2, by: DVec2| HandleSpec::Point {
            rest: p.to_array(),
            translate: by.to_array(),
            rotate: 0.0,
            scale: 1.0,
            depth: 0,
        };
        let mut handles: Vec<HandleSpec> =
            self.fixed.iter().map(|&p| point(p, DVec2::ZERO)).collect();
        handles.push(point(self.moved, self.by));
        let mut project = Project {
            method: Method::Arap,
            handles,
            ..Project::default()
        };
        if let Some(arap) = arap {
            let mut json: serde_json::Value =
                serde_json::from_str(&project.to_json()).expect("a rig file");
            json["arap"] = serde_json::from_str(arap).expect("ARAP settings");
            project = Project::from_json(&json.to_string()).expect("a valid rig");
        }
        project
    }
}

/// An opaque 800 × 600 picture (a gradient with a grid on it), its corners pinned 40 px
/// in, two pins at rest inside, and one pulled by (101, −90).
pub fn opaque() -> PinCase {
    let image = RgbaImage::from_fn(800, 600, |x, y| {
        let line = x % 40 < 2 || y % 40 < 2;
        if line {
            Rgba([20, 20, 20, 255])
        } else {
            Rgba([(x / 4) as u8, (y * 2 / 5) as u8, 160, 255])
        }
    });
    PinCase {
        name: "opaque 800 × 600",
        image,
        fixed: vec![
            DVec2::new(40.0, 40.0),
            DVec2::new(760.0, 40.0),
            DVec2::new(760.0, 560.0),
            DVec2::new(40.0, 560.0),
            DVec2::new(250.0, 400.0),
            DVec2::new(600.0, 200.0),
        ],
        moved: DVec2::new(400.0, 300.0),
        by: DVec2::new(101.0, -90.0),
    }
}

/// A cut-out figure on a transparent 600 × 500 picture: a round body, a head on a
/// neck, two thin arms and two legs. The feet and the body are pinned; the head is
/// pulled up and to the side by (70, −60).
pub fn figure() -> PinCase {
    let image = figure::figure_picture();
    PinCase {
        name: "figure cut-out 600 × 500",
        image,
        fixed: vec![
            DVec2::new(222.0, 462.0),
            DVec2::new(378.0, 462.0),
            DVec2::new(300.0, 270.0),
        ],
        moved: DVec2::new(300.0, 110.0),
        by: DVec2::new(70.0, -60.0),
    }
}

/// Where the warp takes rest point `p`: the deformed mesh interpolated over the rest
/// triangle holding it.
pub fn follow(domain: &weights_core::Domain, deformed: &[DVec2], p: DVec2) -> Option<DVec2> {
    let (t, bary) = domain.locate(p)?;
    let tri = domain.triangles()[t];
    Some((0..3).map(|k| deformed[tri[k] as usize] * bary[k]).sum())
}

/// The picture's mesh at `density` and where ARAP puts its vertices.
pub fn warp(
    case: &PinCase,
    density: usize,
    arap: Option<&str>,
) -> (weights_core::Domain, Vec<DVec2>) {
    let project = case.project(arap);
    let warper = pipeline::prepare_warper(&case.image, &project, Some(density), &())
        .unwrap_or_else(|e| panic!("{} at density {density}: {e:#}", case.name));
    let deformer = &warper.deformer;
    let domain = weights_core::Domain::new(
        deformer.rest().to_vec(),
        deformer.triangles().to_vec(),
        weights_core::Metric::Euclidean,
    )
    .expect("the picture's mesh");
    let deformed = warper.deformer.deformed();
    (domain, deformed)
}

/// Points on a circle of `radius` around `centre` that lie on the shape.
pub fn ring(domain: &weights_core::Domain, centre: DVec2, radius: f64) -> Vec<DVec2> {
    (0..48)
        .map(|k| {
            let a = f64::from(k) / 48.0 * std::f64::consts::TAU;
            centre + radius * DVec2::new(a.cos(), a.sin())
        })
        .filter(|&p| domain.locate(p).is_some())
        .collect()
}

/// How the pins behave at one density.
#[derive(Clone, Copy, Debug)]
pub struct PinReport {
    /// Mesh vertices.
    pub vertices: usize,
    /// The least share of the moved pin's displacement that points 1.5% of the
    /// diagonal from it move along it (≥ 0.7 is the target).
    pub follow: f64,
    /// The largest motion of points 1.5% of the diagonal from a fixed pin, as a share
    /// of the moved pin's displacement (≤ 0.1 is the target).
    pub hold: f64,
    /// Where the moved pin itself went, off its target, in pixels.
    pub pin_error: f64,
    /// Triangles of the picture's mesh turned over (a fold: the picture shows
    /// through itself).
    pub folds: usize,
}

/// Measures `case` at `density`.
pub fn measure(
    case: &PinCase,
    density: usize,
    arap: Option<&str>,
) -> (PinReport, Vec<DVec2>, weights_core::Domain) {
    let (domain, deformed) = warp(case, density, arap);
    let radius = 0.015 * case.diagonal();
    let d = case.by;
    let at = |p: DVec2| follow(&domain, &deformed, p).expect("on the shape");
    let follow = ring(&domain, case.moved, radius)
        .into_iter()
        .map(|p| (at(p) - p).dot(d) / d.length_squared())
        .fold(f64::INFINITY, f64::min);
    let hold = case
        .fixed
        .iter()
        .flat_map(|&f| ring(&domain, f, radius))
        .map(|p| (at(p) - p).length() / d.length())
        .fold(0.0, f64::max);
    let pin_error = at(case.moved).distance(case.moved + d);
    let area = |p: [DVec2; 3]| (p[1] - p[0]).perp_dot(p[2] - p[0]);
    let folds = domain
        .triangles()
        .iter()
        .filter(|t| {
            let rest = t.map(|v| domain.positions()[v as usize]);
            let moved = t.map(|v| deformed[v as usize]);
            area(rest) * area(moved) < 0.0
        })
        .count();
    (
        PinReport {
            vertices: domain.len(),
            follow,
            hold,
            pin_error,
            folds,
        },
        deformed,
        domain,
    )
}

/// The largest distance, as a share of the diagonal, between where two warps of the same
/// picture take points on a grid over it (every 1% of the diagonal).
pub fn largest_difference(
    case: &PinCase,
    a: (&weights_core::Domain, &[DVec2]),
    b: (&weights_core::Domain, &[DVec2]),
) -> f64 {
    let step = 0.01 * case.diagonal();
    let (w, h) = (
        f64::from(case.image.width()),
        f64::from(case.image.height()),
    );
    let mut worst: f64 = 0.0;
    let mut y = 0.5 * step;
    while y < h {
        let mut x = 0.5 * step;
        while x < w {
            let p = DVec2::new(x, y);
            if let (Some(pa), Some(pb)) = (follow(a.0, a.1, p), follow(b.0, b.1, p)) {
                worst = worst.max(pa.distance(pb));
            }
            x += step;
        }
        y += step;
    }
    worst / case.diagonal()
}
