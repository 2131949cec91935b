//! Similarity transforms taken about a centre.

use glam::{DAffine2, DMat2, DVec2};

use crate::distance::closest_point_on_segment;

/// A similarity transform written about a centre `c`: a point `x` goes to
/// `c + translation + scale · R(rotation) · (x − c)`.
///
/// The centre is not stored; the caller gives it on every use (a handle's rest
/// position, say). Written this way, the translation is how far the centre itself
/// moves, and blending the transforms of different handles does not depend on where
/// the origin of the coordinates is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity {
    /// How far the centre moves, in the caller's units (pixels).
    pub translation: DVec2,
    /// Rotation in radians, counter-clockwise in a y-up frame (from `+x` towards `+y`);
    /// in image coordinates (y down) it appears clockwise on screen.
    pub rotation: f64,
    /// Uniform scale factor (1 = none).
    pub scale: f64,
}

impl Default for Similarity {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Similarity {
    /// No motion.
    pub const IDENTITY: Self = Self {
        translation: DVec2::ZERO,
        rotation: 0.0,
        scale: 1.0,
    };

    /// A pure translation.
    pub fn translate(translation: DVec2) -> Self {
        Self {
            translation,
            ..Self::IDENTITY
        }
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.translation.is_finite() && self.rotation.is_finite() && self.scale.is_finite()
    }

    /// Where `x` goes when this transform is taken about `centre`:
    /// `centre + translation + linear() · (x − centre)`.
    #[inline]
    pub fn apply(&self, centre: DVec2, x: DVec2) -> DVec2 {
        centre + self.translation + self.linear() * (x - centre)
    }

    /// The same map as [`Similarity::apply`], rounded in another order: `x − centre` is
    /// rotated first and then scaled, `centre + translation + R(rotation)·(x − centre)
    /// · scale`. The two agree to the last bit when the scale is a power of two, and
    /// within rounding otherwise; a caller that has always used one keeps to it so
    /// that its results do not move.
    #[inline]
    pub fn apply_rotating_first(&self, centre: DVec2, x: DVec2) -> DVec2 {
        centre + self.translation + DMat2::from_angle(self.rotation) * (x - centre) * self.scale
    }

    /// The 2×2 linear part `scale · R(rotation)`.
    #[inline]
    pub fn linear(&self) -> DMat2 {
        DMat2::from_angle(self.rotation) * self.scale
    }

    /// The same map as an affine transform of the plane, for the given centre.
    pub fn to_affine(&self, centre: DVec2) -> DAffine2 {
        let linear = self.linear();
        DAffine2::from_mat2_translation(linear, centre + self.translation - linear * centre)
    }

    /// This transform followed by `next`, both about the same centre: the result's
    /// [`apply`](Similarity::apply) is `next.apply(c, self.apply(c, x))` up to rounding.
    /// Rotations add (they are not wrapped into a turn) and scales multiply.
    pub fn then(&self, next: &Similarity) -> Similarity {
        Similarity {
            translation: next.translation + next.linear() * self.translation,
            rotation: self.rotation + next.rotation,
            scale: self.scale * next.scale,
        }
    }

    /// The transform about the same centre that undoes this one: `inverse.apply(c,
    /// self.apply(c, x))` is `x` up to rounding. `None` for a zero scale (everything
    /// goes to one point) or a non-finite component.
    pub fn inverse(&self) -> Option<Similarity> {
        if self.scale == 0.0 || !self.is_finite() {
            return None;
        }
        let undo = Similarity {
            translation: DVec2::ZERO,
            rotation: -self.rotation,
            scale: 1.0 / self.scale,
        };
        Some(Similarity {
            translation: -(undo.linear() * self.translation),
            ..undo
        })
    }

    /// The transform about `centre` that maps the segment `rest` onto the segment `pose`:
    /// rotation and scale from the segments' directions and lengths, translation such
    /// that the point of `rest` nearest `centre` goes to the point at the same fraction
    /// of `pose`. A zero-length segment (either one) gives no rotation and no scale,
    /// and a zero-length `rest` is taken at its middle.
    pub fn from_segments(centre: DVec2, rest: [DVec2; 2], pose: [DVec2; 2]) -> Self {
        let (a, b) = (rest[1] - rest[0], pose[1] - pose[0]);
        let (rotation, scale) = if a.length_squared() > 0.0 && b.length_squared() > 0.0 {
            (b.to_angle() - a.to_angle(), b.length() / a.length())
        } else {
            (0.0, 1.0)
        };
        let t = if a.length_squared() > 0.0 {
            closest_point_on_segment(centre, rest[0], rest[1]).1
        } else {
            0.5
        };
        let moved_centre = pose[0].lerp(pose[1], t);
        Self {
            translation: moved_centre - rest[0].lerp(rest[1], t),
            rotation,
            scale,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DVec2, b: DVec2) -> bool {
        (a - b).length() <= 1e-12 * (1.0 + a.length().max(b.length()))
    }

    fn samples() -> [Similarity; 4] {
        [
            Similarity {
                translation: DVec2::new(3.0, -2.0),
                rotation: 0.7,
                scale: 1.3,
            },
            Similarity {
                translation: DVec2::new(-0.5, 12.0),
                rotation: -2.9,
                scale: 0.25,
            },
            Similarity::translate(DVec2::new(7.0, 1.5)),
            Similarity::IDENTITY,
        ]
    }

    const POINTS: [DVec2; 3] = [
        DVec2::new(-4.0, 5.5),
        DVec2::new(10.0, 20.0),
        DVec2::new(0.125, -33.0),
    ];

    #[test]
    fn apply_matches_the_affine_form_and_moves_the_centre_by_the_translation() {
        let c = DVec2::new(10.0, 20.0);
        for s in samples() {
            let affine = s.to_affine(c);
            for x in POINTS {
                assert!(close(affine.transform_point2(x), s.apply(c, x)));
            }
            assert_eq!(s.apply(c, c), c + s.translation);
        }
    }

    #[test]
    fn the_identity_moves_nothing_and_is_the_default() {
        assert_eq!(Similarity::default(), Similarity::IDENTITY);
        let c = DVec2::new(1.5, -2.0);
        for x in POINTS {
            assert_eq!(Similarity::IDENTITY.apply(c, x), x);
        }
    }

    #[test]
    fn a_positive_rotation_turns_x_towards_y() {
        let quarter = Similarity {
            rotation: std::f64::consts::FRAC_PI_2,
            ..Similarity::IDENTITY
        };
        assert!(close(quarter.apply(DVec2::ZERO, DVec2::X), DVec2::Y));
    }

    #[test]
    fn both_orders_of_rounding_give_the_same_map() {
        let c = DVec2::new(-3.0, 4.25);
        for s in samples() {
            for x in POINTS {
                assert!(close(s.apply(c, x), s.apply_rotating_first(c, x)));
            }
        }
        // Bit for bit when the scale is a power of two.
        let s = Similarity {
            translation: DVec2::new(0.3, 0.7),
            rotation: 1.1,
            scale: 0.25,
        };
        for x in POINTS {
            assert_eq!(s.apply(c, x), s.apply_rotating_first(c, x));
        }
    }

    #[test]
    fn composing_applies_one_after_the_other() {
        let c = DVec2::new(2.0, -1.0);
        for first in samples() {
            for next in samples() {
                let both = first.then(&next);
                for x in POINTS {
                    assert!(close(both.apply(c, x), next.apply(c, first.apply(c, x))));
                }
            }
        }
    }

    #[test]
    fn the_inverse_undoes_the_transform() {
        let c = DVec2::new(5.0, 5.0);
        for s in samples() {
            let inverse = s.inverse().expect("an invertible sample");
            for x in POINTS {
                assert!(close(inverse.apply(c, s.apply(c, x)), x));
                assert!(close(s.apply(c, inverse.apply(c, x)), x));
            }
            let none = s.then(&inverse);
            assert!(none.translation.length() <= 1e-12 * (1.0 + s.translation.length()));
            assert!(none.rotation.abs() <= 1e-15 && (none.scale - 1.0).abs() <= 1e-15);
        }
        let flat = Similarity {
            scale: 0.0,
            ..Similarity::IDENTITY
        };
        assert_eq!(flat.inverse(), None);
        let broken = Similarity {
            rotation: f64::NAN,
            ..Similarity::IDENTITY
        };
        assert_eq!(broken.inverse(), None);
        assert!(!broken.is_finite());
    }

    #[test]
    fn segments_map_onto_each_other() {
        let rest = [DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0)];
        let pose = [DVec2::new(5.0, 5.0), DVec2::new(5.0, 25.0)];
        for t in [0.0, 0.25, 1.0] {
            let c = rest[0].lerp(rest[1], t);
            let s = Similarity::from_segments(c, rest, pose);
            assert_eq!(s.scale, 2.0);
            for u in [0.0, 0.5, 1.0] {
                let p = rest[0].lerp(rest[1], u);
                let q = pose[0].lerp(pose[1], u);
                assert!((s.apply(c, p) - q).length() < 1e-12);
            }
        }
    }

    #[test]
    fn a_zero_length_segment_gives_a_translation_of_its_middle() {
        let rest = [DVec2::new(1.0, 1.0); 2];
        let pose = [DVec2::new(4.0, 0.0), DVec2::new(6.0, 2.0)];
        let s = Similarity::from_segments(DVec2::new(9.0, 9.0), rest, pose);
        assert_eq!(s, Similarity::translate(DVec2::new(4.0, 0.0)));
        let s = Similarity::from_segments(DVec2::ZERO, pose, [DVec2::new(3.0, 3.0); 2]);
        assert_eq!((s.rotation, s.scale), (0.0, 1.0));
    }
}
