//! What C2Warp's fuzz targets check, one function per target. Each takes the fuzzer's
//! bytes, feeds them to one entry point that reads user input, and panics only if a
//! property fails — an `Err` for bad input is the right answer, a panic never is.
//!
//! The targets themselves (`fuzz/`, run with cargo-fuzz on a nightly toolchain) are
//! one line each around these functions, and `tests/replay.rs` replays every crash
//! found so far and the kept corpus on stable, so a fixed crash stays fixed.

use std::io::Cursor;
use std::sync::OnceLock;

use arbitrary::Unstructured;
use glam::DVec2;
use weights_core::{Domain, Handle, Metric, Placement, Rig, RigOptions, Similarity};

/// The rig-file parser: any text either parses into a project that validates and
/// round-trips through its JSON exactly, or is refused with an error.
pub fn rig_file(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(project) = project::Project::from_json(text) else {
        return;
    };
    project.validate(None).expect("a parsed project validates");
    let again = project::Project::from_json(&project.to_json()).expect("its own JSON parses");
    assert_eq!(again, project, "a project round-trips through its JSON");
    // Validation against a picture size never panics either.
    let _ = project.validate(Some((64, 48)));
    animated(&project);
}

/// A valid project's animation gives, at any time and any cursor, a pose that poses
/// the project into a valid one (finite, in range), and each key's own pose at its time.
fn animated(project: &project::Project) {
    let Some(animation) = &project.animation else {
        return;
    };
    let last = animation.duration();
    for time in [-1.0, 0.0, 0.37 * last, 0.5 * last, last, last + 1.0] {
        let posed = animation::posed_at(project, time);
        if let Err(e) = posed.validate(None) {
            panic!("the pose at {time} s poses the rig into an invalid one: {e}");
        }
    }
    for key in &animation.keys {
        let pose = animation::pose_at(project, key.time).expect("a pose with keys");
        assert_eq!(
            pose.handles, key.pose.handles,
            "the pose at a key's time is the key's"
        );
    }
    if let Some(blend) = animation::SpatialBlend::of(project) {
        let weights = blend.weights([3.0, -7.0]);
        assert!(
            weights.iter().all(|w| w.is_finite()),
            "finite blend weights"
        );
        if let Some(pose) = blend.pose(project, [3.0, -7.0]) {
            // Far-off markers may blend beyond the pose limits; finite is what counts.
            let numbers = pose.handles.iter().flat_map(|h| match *h {
                project::HandlePose::Point {
                    translate,
                    rotate,
                    scale,
                } => vec![translate[0], translate[1], rotate, scale],
                project::HandlePose::Bar { pose } => pose.iter().flatten().copied().collect(),
            });
            let cage = pose.cage.iter().flatten().flatten().copied();
            assert!(
                numbers.chain(cage).all(f64::is_finite),
                "a finite blended pose"
            );
        }
    }
}

/// The OBJ reader: any bytes either read into a mesh whose indices are in range and
/// which writes and reads back the same, or are refused with an error.
pub fn obj_mesh(data: &[u8]) {
    let Ok(mesh) = mesh::Mesh::read_obj(Cursor::new(data)) else {
        return;
    };
    let n = mesh.vertices.len();
    assert!(
        mesh.triangles.iter().flatten().all(|&v| (v as usize) < n),
        "a triangle names a vertex that does not exist"
    );
    assert!(
        mesh.vertices.iter().all(|p| p.is_finite()),
        "non-finite vertex"
    );
    let mut written = Vec::new();
    mesh.write_obj(&mut written).expect("writes to memory");
    let back = mesh::Mesh::read_obj(Cursor::new(&written)).expect("its own OBJ reads");
    assert_eq!(back.vertices, mesh.vertices, "vertices round-trip");
    assert_eq!(back.triangles, mesh.triangles, "triangles round-trip");
}

/// The layered readers (PSD, OpenRaster): any bytes either read into layers that lie
/// on the canvas, each with a visible pixel, an opacity in 0..=1 and at most
/// `MAX_LAYERS` of them, that flatten to the canvas's size; or are refused.
pub fn layered(data: &[u8]) {
    let limits = render::ImageLimits {
        max_width: 512,
        max_height: 512,
        max_alloc_bytes: 64 << 20,
    };
    let Ok(artwork) = layers::decode(data, &limits) else {
        return;
    };
    assert!(artwork.width <= 512 && artwork.height <= 512);
    assert!(artwork.layers.len() <= layers::MAX_LAYERS);
    for layer in &artwork.layers {
        let (w, h) = layer.dimensions();
        assert!(w > 0 && h > 0, "an empty layer is dropped");
        assert!(layer.x >= 0 && layer.y >= 0, "clipped to the canvas");
        assert!(layer.x as u64 + u64::from(w) <= u64::from(artwork.width));
        assert!(layer.y as u64 + u64::from(h) <= u64::from(artwork.height));
        assert!((0.0..=1.0).contains(&layer.opacity));
    }
    assert_eq!(
        artwork.flatten().dimensions(),
        (artwork.width, artwork.height)
    );
}

/// Image decoding and meshing: any bytes either decode (under small limits) into a
/// picture that meshes into a valid mesh covering every visible pixel, or are refused.
/// The first byte picks the mesh density; after it, bytes that start with `M` are a
/// raw alpha mask (width and height from the next two bytes, then one alpha per
/// pixel), so the fuzzer can draw shapes directly; anything else is an image file.
pub fn image_mesh(data: &[u8]) {
    let Some((&density, bytes)) = data.split_first() else {
        return;
    };
    let picture = match bytes {
        [b'M', w, h, alphas @ ..] => {
            let (w, h) = (u32::from(*w % 64) + 1, u32::from(*h % 64) + 1);
            image::RgbaImage::from_fn(w, h, |x, y| {
                let a = alphas.get((y * w + x) as usize).copied().unwrap_or(0);
                image::Rgba([200, 100, 50, a])
            })
        }
        _ => {
            let limits = render::ImageLimits {
                max_width: 512,
                max_height: 512,
                max_alloc_bytes: 64 << 20,
            };
            let Ok(picture) = render::decode_image(bytes, &limits) else {
                return;
            };
            picture
        }
    };
    assert!(picture.width() <= 512 && picture.height() <= 512);
    let options = mesh::MeshOptions {
        target_vertices: 16 + usize::from(density) * 8,
        ..mesh::MeshOptions::default()
    };
    let constraints = mesh::Constraints {
        points: &[],
        polylines: &[],
    };
    let Ok(meshed) = mesh::mesh_image(
        &picture,
        &mesh::DomainOptions::default(),
        &options,
        &constraints,
    ) else {
        assert!(
            picture.pixels().all(|p| p.0[3] == 0),
            "only a picture with nothing visible may fail to mesh"
        );
        return;
    };
    meshed.mesh.sanity_check().expect("a valid mesh");
    // Every visible pixel's centre is inside the mesh.
    let covered = coverage(&meshed.mesh, picture.width(), picture.height());
    for (x, y, p) in picture.enumerate_pixels() {
        assert!(
            p.0[3] == 0 || covered[(y * picture.width() + x) as usize],
            "visible pixel ({x}, {y}) is not meshed"
        );
    }
}

/// Which pixel centres of a `width` × `height` picture lie in a triangle of `mesh`
/// (boundary included).
fn coverage(mesh: &mesh::Mesh, width: u32, height: u32) -> Vec<bool> {
    let mut covered = vec![false; (width * height) as usize];
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle_positions(t);
        let area = (b - a).perp_dot(c - a);
        if area == 0.0 {
            continue;
        }
        let lo = a.min(b).min(c).floor().max(DVec2::ZERO);
        let hi = a.max(b).max(c).ceil();
        for y in lo.y as u32..(hi.y as u32).min(height) {
            for x in lo.x as u32..(hi.x as u32).min(width) {
                let p = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
                let u = (b - p).perp_dot(c - p) / area;
                let v = (c - p).perp_dot(a - p) / area;
                if u >= -1e-9 && v >= -1e-9 && u + v <= 1.0 + 1e-9 {
                    covered[(y * width + x) as usize] = true;
                }
            }
        }
    }
    covered
}

/// A small cut-out to put handles on: a 40 × 30 rectangle with a square hole and a
/// notch, meshed at about 600 vertices, intrinsic distances.
fn small_domain() -> &'static Domain {
    static DOMAIN: OnceLock<Domain> = OnceLock::new();
    DOMAIN.get_or_init(|| {
        let picture = image::RgbaImage::from_fn(40, 30, |x, y| {
            let hole = (15..22).contains(&x) && (10..17).contains(&y);
            let notch = x > 30 && (12..15).contains(&y);
            image::Rgba([90, 90, 90, if hole || notch { 0 } else { 255 }])
        });
        let options = mesh::MeshOptions {
            target_vertices: 600,
            ..mesh::MeshOptions::default()
        };
        let constraints = mesh::Constraints {
            points: &[],
            polylines: &[],
        };
        let meshed = mesh::mesh_image(
            &picture,
            &mesh::DomainOptions::default(),
            &options,
            &constraints,
        )
        .expect("the test shape meshes");
        Domain::new(
            meshed.mesh.vertices,
            meshed.mesh.triangles,
            Metric::Intrinsic,
        )
        .expect("a valid domain")
    })
}

/// A coordinate the fuzzer picks: mostly on or near the shape, sometimes anything,
/// NaN and infinities included.
fn coordinate(u: &mut Unstructured<'_>, extent: f64) -> arbitrary::Result<f64> {
    Ok(match u.int_in_range(0..=9u8)? {
        0 => f64::from_bits(u.arbitrary()?),
        1 => *u.choose(&[f64::NAN, f64::INFINITY, -1.0, 0.0, extent, 1e300])?,
        _ => f64::from(u.int_in_range(0..=4000u16)?) * extent / 4000.0,
    })
}

fn handles(u: &mut Unstructured<'_>) -> arbitrary::Result<Vec<Handle>> {
    let count = u.int_in_range(0..=6u8)?;
    let point = |u: &mut Unstructured<'_>| -> arbitrary::Result<DVec2> {
        Ok(DVec2::new(coordinate(u, 40.0)?, coordinate(u, 30.0)?))
    };
    (0..count)
        .map(|_| {
            Ok(if u.ratio(2, 3)? {
                Handle::Point {
                    rest: point(u)?,
                    transform: Similarity {
                        translation: point(u)?,
                        rotation: coordinate(u, 7.0)?,
                        scale: coordinate(u, 3.0)?,
                    },
                }
            } else {
                Handle::Bar {
                    rest: [point(u)?, point(u)?],
                    pose: [point(u)?, point(u)?],
                }
            })
        })
        .collect()
}

/// `Rig::new` and then `Rig::set_handles` with arbitrary handle sets on a small
/// cut-out: each either fails with an error and leaves the rig as it was, or gives
/// weights that sum to one, are non-negative, and equal those of a rebuild with the
/// same handles and virtual handles.
pub fn rig_handles(data: &[u8]) {
    let mut u = Unstructured::new(data);
    let (Ok(first), Ok(second)) = (handles(&mut u), handles(&mut u)) else {
        return;
    };
    let options = RigOptions {
        alpha: u.int_in_range(0..=4u8).map_or(1.0, |a| f64::from(a) / 4.0),
        fixed_boundary: u.arbitrary().unwrap_or(false),
        placement: if u.arbitrary().unwrap_or(false) {
            Placement::Symmetric
        } else {
            Placement::AsWritten
        },
        ..RigOptions::default()
    };
    let domain = small_domain().clone();
    let Ok(mut rig) = Rig::new(domain, first, options) else {
        return;
    };
    check_rig(&rig);
    let before = rig.handles().to_vec();
    match rig.set_handles(second) {
        Ok(()) => check_rig(&rig),
        Err(_) => assert_eq!(
            rig.handles(),
            before.as_slice(),
            "a failed update changes nothing"
        ),
    }
}

fn check_rig(rig: &Rig) {
    let nodes = rig.nodes().len();
    for v in 0..rig.domain().len() {
        let mut sum = 0.0;
        let mut any = false;
        for (k, w) in rig.weights(v) {
            assert!(
                k < nodes && w.is_finite() && w >= 0.0,
                "weight {w} on node {k}"
            );
            sum += w;
            any = true;
        }
        assert!(!any || (sum - 1.0).abs() < 1e-9, "weights sum to {sum}");
    }
    assert!(
        rig.deform().iter().all(|p| p.is_finite()),
        "finite deformation"
    );
    let rebuilt = Rig::with_virtual_handles(
        rig.domain().clone(),
        rig.handles().to_vec(),
        &rig.virtual_vertices(),
        rig.options().clone(),
    )
    .expect("a rebuild with the same nodes");
    rig.same_weights_as(&rebuilt)
        .expect("the same weights as a rebuild");
}
