//! ARAP's pins behave like Puppet Warp pins at the densities artists use: what lies
//! near a moved pin goes with it, what lies near a fixed pin stays, and the warp does
//! not depend on how fine the picture is meshed (see `support/pins.rs`).

use crate::support;

use support::pins;

/// Points 1.5% of the diagonal from a moved pin move at least this share of its
/// displacement along it…
const FOLLOW: f64 = 0.7;
/// …points as close to a fixed pin at most this share…
const HOLD: f64 = 0.1;
/// …and warps at 5,000 and 80,000 vertices differ by at most this share of the
/// diagonal anywhere.
const SAME: f64 = 0.01;

fn check(case: &pins::PinCase) {
    let (coarse, coarse_warp, coarse_mesh) = pins::measure(case, 5_000, None);
    let (fine, fine_warp, fine_mesh) = pins::measure(case, 80_000, None);
    for report in [coarse, fine] {
        assert!(report.follow >= FOLLOW, "{}: {report:?}", case.name);
        assert!(report.hold <= HOLD, "{}: {report:?}", case.name);
        assert!(report.pin_error < 1e-6, "{}: {report:?}", case.name);
    }
    let apart =
        pins::largest_difference(case, (&coarse_mesh, &coarse_warp), (&fine_mesh, &fine_warp));
    assert!(
        apart <= SAME,
        "{}: {:.2}% of the diagonal",
        case.name,
        100.0 * apart
    );
}

#[test]
fn pins_follow_and_hold_on_an_opaque_picture_at_any_density() {
    check(&pins::opaque());
}

#[test]
fn pins_follow_and_hold_on_a_cut_out_at_any_density() {
    let case = pins::figure();
    check(&case);
    // A limb pulled by its pin keeps its shape: no triangle of the picture turns over.
    let (report, _, _) = pins::measure(&case, 20_000, None);
    assert_eq!(report.folds, 0, "{report:?}");
}

#[test]
fn the_papers_single_vertex_pins_stay_reachable_and_lose_their_grip() {
    // With pin_radius 0 and ARAP on a mesh as fine as the picture's, a pin holds its
    // one vertex: what the paper does, and why the defaults are what they are.
    let case = pins::opaque();
    let paper = r#"{"pin_radius": 0, "density": 20000}"#;
    let (report, _, _) = pins::measure(&case, 20_000, Some(paper));
    assert!(report.follow < FOLLOW && report.hold > HOLD, "{report:?}");
}
