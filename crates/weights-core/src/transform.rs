//! Similarity transforms expressed about a handle's own rest position.

use glam::{DAffine2, DMat2, DVec2};

/// A similarity transform written in a handle's own frame: a point `x` of the rest
/// image goes to `c + translation + scale · R(rotation) · (x − c)`, where `c` is the
/// handle's rest position. Written this way, blending transforms of different handles
/// does not depend on where the image origin is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity {
    /// Displacement of the handle itself, in pixels.
    pub translation: DVec2,
    /// Counter-clockwise rotation in radians, in image coordinates (y down, so it
    /// appears clockwise on screen).
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

    /// Where `x` goes when this transform is taken about the centre `c`.
    #[inline]
    pub fn apply(&self, centre: DVec2, x: DVec2) -> DVec2 {
        centre + self.translation + self.linear() * (x - centre)
    }

    /// The 2×2 linear part `scale · R(rotation)`.
    #[inline]
    pub fn linear(&self) -> DMat2 {
        DMat2::from_angle(self.rotation) * self.scale
    }

    /// The same map as an affine transform in image coordinates.
    pub fn to_affine(&self, centre: DVec2) -> DAffine2 {
        let linear = self.linear();
        DAffine2::from_mat2_translation(linear, centre + self.translation - linear * centre)
    }

    /// The transform about `centre` that maps the segment `rest` onto the segment `pose`
    /// (rotation and scale from the segments' directions and lengths). A zero-length
    /// segment gives no rotation and no scale.
    pub fn from_segments(centre: DVec2, rest: [DVec2; 2], pose: [DVec2; 2]) -> Self {
        let (a, b) = (rest[1] - rest[0], pose[1] - pose[0]);
        let (rotation, scale) = if a.length_squared() > 0.0 && b.length_squared() > 0.0 {
            (b.to_angle() - a.to_angle(), b.length() / a.length())
        } else {
            (0.0, 1.0)
        };
        let t = if a.length_squared() > 0.0 {
            ((centre - rest[0]).dot(a) / a.length_squared()).clamp(0.0, 1.0)
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

    #[test]
    fn apply_matches_affine() {
        let s = Similarity {
            translation: DVec2::new(3.0, -2.0),
            rotation: 0.7,
            scale: 1.3,
        };
        let c = DVec2::new(10.0, 20.0);
        let x = DVec2::new(-4.0, 5.5);
        let a = s.to_affine(c);
        assert!((a.transform_point2(x) - s.apply(c, x)).length() < 1e-12);
        assert_eq!(s.apply(c, c), c + s.translation);
    }

    #[test]
    fn segments_map_onto_each_other() {
        let rest = [DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0)];
        let pose = [DVec2::new(5.0, 5.0), DVec2::new(5.0, 25.0)];
        for t in [0.0, 0.25, 1.0] {
            let c = rest[0].lerp(rest[1], t);
            let s = Similarity::from_segments(c, rest, pose);
            for u in [0.0, 0.5, 1.0] {
                let p = rest[0].lerp(rest[1], u);
                let q = pose[0].lerp(pose[1], u);
                assert!((s.apply(c, p) - q).length() < 1e-12);
            }
        }
    }
}
