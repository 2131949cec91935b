//! Moving least squares image deformation, as Schaefer, McPhail and Warren give it
//! ("Image Deformation Using Moving Least Squares", SIGGRAPH 2006): the affine
//! (§2.1), similarity (§2.2) and rigid (§2.3) deformations, with point handles and
//! with line-segment handles ("bars", §4).
//!
//! The crate knows points in the plane, in pixels (image space); it knows nothing
//! of images, meshes or screens. At every rest vertex `v` it fits the transformation
//! `l_v` of the chosen class that best maps the rest controls onto the posed ones,
//! each control weighted by `1 / |p − v|^{2α}`, and moves `v` to `l_v(v)`.
//!
//! The work is split in two:
//! 1. [`Mls::new`], once per set of rest vertices and rest controls: weights, the
//!    bars' integrals, centroids and moment matrices — everything that depends on
//!    rest positions only — leaving per vertex one small coefficient per posed
//!    control position (for similarity and rigid a complex number, i.e. a 2×2
//!    matrix `[[a, b], [−b, a]]`, plus the centroid weight; for affine a scalar);
//! 2. [`Mls::deform`], per pose: a few multiply-adds per vertex and control
//!    position, in parallel over vertices.
//!
//! [`deform_point`] evaluates one point without a table.
//!
//! # Reading the paper
//!
//! Where the text leaves a choice, this crate takes these (`docs/methods/mls.md`
//! has the formulas and the reasons):
//! - A bar's weight `w(t) = 1/|p(t) − v|^{2α}` is integrated with respect to arc
//!   length, so a bar weighs the same as its two collinear halves. The closed forms
//!   for the bar integrals carried by public implementations hold for α = 2 only
//!   and lose digits near the bar's line; here the integrals are computed by
//!   Gauss–Legendre quadrature (with the substitution `s = h·tan θ` near the foot of
//!   the perpendicular) to about 1e-13 relative, for any α > 0.
//! - α is one number for point and bar handles alike (default 1). Point weights
//!   (px^{−2α}) and bar integrals (px^{1−2α}) are added as the paper adds them, in
//!   pixels: their balance depends on the unit.
//! - Point handles act by position only: a handle's rotation or scale does not enter.
//! - Weights are Euclidean: a handle pulls everything near it in the plane, whatever
//!   the shape between them.
//! - Degenerate fits have defined answers, never NaN: no controls is the identity; a
//!   vertex on a point handle goes to its posed position (the mean, if several
//!   coincide there); a vertex on a bar (α ≥ ½) goes to the same parameter on the
//!   posed bar; where the linear part is undetermined (one point handle, or all
//!   point handles at one place) similarity and rigid translate by `q* − p*`;
//!   affine falls back to similarity at a vertex whose moment matrix is singular
//!   (fewer than three non-collinear positions in effect, or a single bar); rigid
//!   translates by `q* − p*` where `f⃗_r` vanishes. Zero-length bars are refused.
//!
//! ```
//! use glam::DVec2;
//! use mls::{Control, MlsOptions, Variant, deform_point};
//!
//! // Three point handles; turn them all a quarter turn about the origin.
//! let rest = [
//!     Control::Point(DVec2::new(10.0, 0.0)),
//!     Control::Point(DVec2::new(0.0, 10.0)),
//!     Control::Point(DVec2::new(-10.0, 0.0)),
//! ];
//! let posed = [
//!     Control::Point(DVec2::new(0.0, 10.0)),
//!     Control::Point(DVec2::new(-10.0, 0.0)),
//!     Control::Point(DVec2::new(0.0, -10.0)),
//! ];
//! for variant in [Variant::Affine, Variant::Similarity, Variant::Rigid] {
//!     let options = MlsOptions { variant, ..MlsOptions::default() };
//!     let f = deform_point(DVec2::new(3.0, 4.0), &rest, &posed, &options)?;
//!     assert!((f - DVec2::new(-4.0, 3.0)).length() < 1e-9);
//! }
//! # Ok::<(), mls::MlsError>(())
//! ```

mod error;
mod precompute;
mod quadrature;
mod segment;
mod table;

use glam::DVec2;

pub use error::MlsError;
pub use table::{Mls, deform_point};

/// The class of transformation fitted at every vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Variant {
    /// Any affine map (§2.1): can shear and scale non-uniformly.
    Affine,
    /// Rotation, uniform scale and translation (§2.2).
    Similarity,
    /// Rotation and translation (§2.3); the default.
    #[default]
    Rigid,
}

/// Options of the deformation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlsOptions {
    /// The weight exponent α: a control at distance `r` pixels weighs
    /// `1 / r^{2α}` (a bar: that, integrated along its length). Finite and positive;
    /// default 1. Larger α makes handles more local.
    pub alpha: f64,
    /// The class of transformation; default [`Variant::Rigid`].
    pub variant: Variant,
}

impl Default for MlsOptions {
    fn default() -> Self {
        MlsOptions {
            alpha: 1.0,
            variant: Variant::Rigid,
        }
    }
}

/// A handle, by its position(s) in pixels (image space): at rest, or posed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Control {
    /// A point handle.
    Point(DVec2),
    /// A line-segment handle from its first end to its second. A posed bar's ends
    /// correspond to the rest bar's ends in order; the parameter along the bar maps
    /// linearly.
    Bar([DVec2; 2]),
}
