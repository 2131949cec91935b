//! The long-limbed cut-out figure the ARAP tests and examples pose (included by
//! `energy.rs` and `pins.rs`).

use glam::DVec2;
use image::{Rgba, RgbaImage};

/// A long-limbed cut-out on a transparent `600 × 500` picture: a round body, a head
/// on a neck, two thin arms straight out and two legs.
pub fn figure_picture() -> RgbaImage {
    RgbaImage::from_fn(600, 500, |x, y| {
        let p = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
        let segment = |a: DVec2, b: DVec2| {
            let ab = b - a;
            let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
            p.distance(a + t * ab)
        };
        let body = p.distance(DVec2::new(300.0, 260.0)) < 80.0;
        let head = p.distance(DVec2::new(300.0, 120.0)) < 45.0;
        let neck = segment(DVec2::new(300.0, 150.0), DVec2::new(300.0, 190.0)) < 14.0;
        let arms = segment(DVec2::new(120.0, 200.0), DVec2::new(480.0, 200.0)) < 7.0;
        let legs = segment(DVec2::new(260.0, 320.0), DVec2::new(220.0, 470.0)) < 12.0
            || segment(DVec2::new(340.0, 320.0), DVec2::new(380.0, 470.0)) < 12.0;
        if body || head || neck || arms || legs {
            let stripe = (x / 12 + y / 12) % 2 == 0;
            Rgba(if stripe {
                [230, 120, 40, 255]
            } else {
                [40, 90, 200, 255]
            })
        } else {
            Rgba([0, 0, 0, 0])
        }
    })
}
