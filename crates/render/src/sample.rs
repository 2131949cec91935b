//! Bilinear texture sampling in premultiplied alpha.
//!
//! Texture positions are handled in 32.32 fixed point, so that stepping along
//! a span is an exact integer addition and splitting a position into texel
//! index and fraction needs no floating-point rounding.

/// Sampling positions closer than this (in texels) to a texel centre are
/// snapped onto it, so that an identity map reproduces texels exactly despite
/// floating-point rounding.
pub(crate) const SNAP_TEXELS: f64 = 1e-4;

/// Fractional bits of a fixed-point texture position.
const FRAC_BITS: u32 = 32;
/// One texel in fixed point.
pub(crate) const FIXED_ONE: f64 = (1u64 << FRAC_BITS) as f64;
const FRAC_MASK: i64 = (1 << FRAC_BITS) - 1;
const HALF_TEXEL: i64 = 1 << (FRAC_BITS - 1);
/// [`SNAP_TEXELS`] in fixed point, and one texel minus it.
const SNAP_LO: i64 = (SNAP_TEXELS * FIXED_ONE) as i64;
const SNAP_HI: i64 = (1 << FRAC_BITS) - SNAP_LO;
/// Fixed-point positions may range over `±FIXED_RANGE` texels; beyond that
/// a position is clamped before conversion (it lies far outside any texture).
pub(crate) const FIXED_RANGE: f64 = (1u64 << 30) as f64;

/// Converts a texture coordinate to fixed point, clamping far-away values
/// (NaN becomes 0, as `as` casts do).
#[inline]
pub(crate) fn to_fixed(coordinate: f64) -> i64 {
    (coordinate.clamp(-FIXED_RANGE, FIXED_RANGE) * FIXED_ONE) as i64
}

/// Converts a per-pixel step in texels to fixed point, rounded to nearest
/// (without a libm call), clamped like [`to_fixed`].
#[inline]
pub(crate) fn step_to_fixed(step: f64) -> i64 {
    let scaled = step.clamp(-FIXED_RANGE, FIXED_RANGE) * FIXED_ONE;
    (scaled + 0.5f64.copysign(scaled)) as i64
}

/// The position of the last texel centre along an axis of `size` texels,
/// relative to the first, in fixed point (texels past 2^30 are unreachable).
fn last_centre(size: u32) -> i64 {
    i64::from(size.saturating_sub(1)).min(1 << 30) << FRAC_BITS
}

/// A channel type a [`Texture`] can hold: `u8` or `u16`.
pub(crate) trait Texel: Copy + Default + PartialEq + Send + Sync + 'static {
    /// Weighted premultiplied average of four texels whose weights sum to
    /// `WEIGHT_ONE²`.
    fn blend(taps: &[([Self; 4], u64); 4]) -> [Self; 4];

    /// `top` composited over `base` (straight alpha; see [`crate::over`]).
    fn over(top: [Self; 4], base: [Self; 4]) -> [Self; 4];
}

impl Texel for u8 {
    #[inline(always)]
    fn blend(taps: &[([u8; 4], u64); 4]) -> [u8; 4] {
        blend(taps)
    }

    #[inline]
    fn over(top: [u8; 4], base: [u8; 4]) -> [u8; 4] {
        crate::composite::over(top, base)
    }
}

impl Texel for u16 {
    #[inline(always)]
    fn blend(taps: &[([u16; 4], u64); 4]) -> [u16; 4] {
        blend16(taps)
    }

    #[inline]
    fn over(top: [u16; 4], base: [u16; 4]) -> [u16; 4] {
        crate::composite::over16(top, base)
    }
}

/// A borrowed RGBA texture (8 or 16 bits per channel) with clamp-to-edge
/// bilinear sampling.
pub(crate) struct Texture<'a, C = u8> {
    data: &'a [C],
    width: usize,
    /// Position of the last texel column / row, in fixed point.
    max_x: i64,
    max_y: i64,
}

impl<'a, C: Texel> Texture<'a, C> {
    /// Wraps `data` (row-major RGBA, `width × height`, both non-zero).
    pub(crate) fn new(data: &'a [C], width: u32, height: u32) -> Self {
        Self {
            data,
            width: width as usize,
            max_x: last_centre(width),
            max_y: last_centre(height),
        }
    }

    #[inline]
    fn texel(&self, x: usize, y: usize) -> [C; 4] {
        let i = (y * self.width + x) * 4;
        match self.data.get(i..i + 4) {
            Some(&[r, g, b, a]) => [r, g, b, a],
            _ => [C::default(); 4],
        }
    }

    /// Samples at texture position `(u, v)` in source pixels (texel `(i, j)`
    /// has its centre at `(i + 0.5, j + 0.5)`).
    #[cfg(test)]
    pub(crate) fn sample(&self, u: f64, v: f64) -> [C; 4] {
        self.sample_fixed(to_fixed(u), to_fixed(v))
    }

    /// Samples at texture position `(u, v)` given in fixed point (see
    /// [`to_fixed`]).
    ///
    /// Colours are premultiplied by alpha before filtering and divided by the
    /// filtered alpha afterwards, so a transparent neighbour contributes
    /// coverage but no colour (no dark fringes on cut-outs). Filter weights
    /// have 16 fractional bits and are accumulated exactly in integers.
    #[inline(always)]
    pub(crate) fn sample_fixed(&self, u: i64, v: i64) -> [C; 4] {
        let (x0, x1, fx) = axis(u, self.max_x);
        let (y0, y1, fy) = axis(v, self.max_y);
        if fx == 0 && fy == 0 {
            return self.texel(x0, y0);
        }
        let (gx, gy) = (WEIGHT_ONE - fx, WEIGHT_ONE - fy);
        C::blend(&[
            (self.texel(x0, y0), gx * gy),
            (self.texel(x1, y0), fx * gy),
            (self.texel(x0, y1), gx * fy),
            (self.texel(x1, y1), fx * fy),
        ])
    }
}

/// Fractional bits of a bilinear weight along one axis.
const WEIGHT_BITS: u32 = 16;
/// Weight one along one axis; the product of two axes' weights has
/// `2 * WEIGHT_BITS` fractional bits.
const WEIGHT_ONE: u64 = 1 << WEIGHT_BITS;

/// Splits one fixed-point texture coordinate into the two texel indices to
/// blend and the weight of the second (of [`WEIGHT_ONE`]), clamping to the
/// texel centres `[0, max]` and snapping onto a texel centre within
/// [`SNAP_TEXELS`].
#[inline]
fn axis(coordinate: i64, max: i64) -> (usize, usize, u64) {
    let s = (coordinate - HALF_TEXEL).max(0).min(max);
    let i0 = (s >> FRAC_BITS) as usize;
    let frac = s & FRAC_MASK;
    if frac < SNAP_LO {
        (i0, i0, 0)
    } else if frac > SNAP_HI {
        // `i0 < s <= max` and `max` is whole, so `i0 + 1 <= max`.
        (i0 + 1, i0 + 1, 0)
    } else {
        // Strictly between 0 and WEIGHT_ONE thanks to the snapping margins.
        let weight = (frac + (1 << (FRAC_BITS - WEIGHT_BITS - 1))) >> (FRAC_BITS - WEIGHT_BITS);
        (i0, i0 + 1, weight as u64)
    }
}

/// Rounds a float channel to a byte (saturating; NaN becomes 0).
#[inline]
fn to_u8(v: f32) -> u8 {
    (v + 0.5) as u8
}

/// Weighted premultiplied average of texels; the weights sum to
/// `WEIGHT_ONE²`.
#[inline(always)]
fn blend(taps: &[([u8; 4], u64); 4]) -> [u8; 4] {
    const SHIFT: u32 = 2 * WEIGHT_BITS;
    const HALF: u64 = 1 << (SHIFT - 1);
    // Straight weighted average (≤ 2^40 per channel), rounded.
    let straight = || {
        let mut sums = [0u64; 3];
        for &(texel, weight) in taps {
            for (sum, &c) in sums.iter_mut().zip(&texel[..3]) {
                *sum += weight * u64::from(c);
            }
        }
        sums.map(|c| ((c + HALF) >> SHIFT) as u8)
    };
    if taps.iter().all(|(texel, _)| texel[3] == 255) {
        // Opaque (the common case): premultiplying changes nothing.
        let [r, g, b] = straight();
        return [r, g, b, 255];
    }
    // Σ w·a (≤ 2^40) and Σ w·a·c (≤ 2^48): exact in u64.
    let mut alpha = 0u64;
    let mut premultiplied = [0u64; 3];
    for &(texel, weight) in taps {
        let wa = weight * u64::from(texel[3]);
        alpha += wa;
        for (sum, &c) in premultiplied.iter_mut().zip(&texel[..3]) {
            *sum += wa * u64::from(c);
        }
    }
    if alpha > 0 {
        // The sums fit in i64, whose conversion to f32 is one instruction.
        let inv = 1.0 / alpha as i64 as f32;
        let [r, g, b] = premultiplied.map(|c| to_u8(c as i64 as f32 * inv));
        [r, g, b, ((alpha + HALF) >> SHIFT) as u8]
    } else {
        // Fully transparent: keep the (straight) filtered colour under it.
        let [r, g, b] = straight();
        [r, g, b, 0]
    }
}

/// [`blend`] for 16-bit channels.
#[inline(always)]
fn blend16(taps: &[([u16; 4], u64); 4]) -> [u16; 4] {
    const SHIFT: u32 = 2 * WEIGHT_BITS;
    const HALF: u64 = 1 << (SHIFT - 1);
    // Straight weighted average (≤ 2^48 per channel), rounded.
    let straight = || {
        let mut sums = [0u64; 3];
        for &(texel, weight) in taps {
            for (sum, &c) in sums.iter_mut().zip(&texel[..3]) {
                *sum += weight * u64::from(c);
            }
        }
        sums.map(|c| ((c + HALF) >> SHIFT) as u16)
    };
    if taps.iter().all(|(texel, _)| texel[3] == u16::MAX) {
        let [r, g, b] = straight();
        return [r, g, b, u16::MAX];
    }
    // Σ w·a ≤ 2^32·65535 < 2^48 and Σ w·a·c ≤ 2^32·65535² < 2^64: exact in u64.
    let mut alpha = 0u64;
    let mut premultiplied = [0u64; 3];
    for &(texel, weight) in taps {
        let wa = weight * u64::from(texel[3]);
        alpha += wa;
        for (sum, &c) in premultiplied.iter_mut().zip(&texel[..3]) {
            *sum += wa * u64::from(c);
        }
    }
    if alpha > 0 {
        let inv = 1.0 / alpha as f64;
        let [r, g, b] = premultiplied.map(|c| (c as f64 * inv + 0.5) as u16);
        [r, g, b, ((alpha + HALF) >> SHIFT) as u16]
    } else {
        let [r, g, b] = straight();
        [r, g, b, 0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texel_centres_are_exact() {
        let data: Vec<u8> = (0..2 * 2 * 4).map(|i| i as u8 * 13).collect();
        let t = Texture::new(&data, 2, 2);
        assert_eq!(t.sample(0.5, 0.5), [0, 13, 26, 39]);
        assert_eq!(t.sample(1.5 + 3e-5, 1.5 - 3e-5), [156, 169, 182, 195]);
    }

    #[test]
    fn clamps_to_edge() {
        let data: [u8; 8] = [10, 20, 30, 40, 50, 60, 70, 80];
        let t = Texture::new(&data, 2, 1);
        assert_eq!(t.sample(-100.0, 0.5), [10, 20, 30, 40]);
        assert_eq!(t.sample(100.0, -7.0), [50, 60, 70, 80]);
        // Must not panic; the value is unspecified.
        let _ = t.sample(f64::NAN, f64::INFINITY);
    }

    #[test]
    fn premultiplied_half_way_has_no_dark_fringe() {
        let data: [u8; 8] = [255, 0, 0, 255, 0, 0, 0, 0];
        let t = Texture::new(&data, 2, 1);
        assert_eq!(t.sample(1.0, 0.5), [255, 0, 0, 128]);
    }

    #[test]
    fn sixteen_bits_blend_like_eight() {
        // The same texels widened to 16 bits (×257) sample to the 8-bit result
        // widened, within rounding.
        let narrow: [u8; 16] = [
            255, 0, 0, 255, 0, 0, 0, 0, 10, 200, 30, 128, 90, 80, 70, 255,
        ];
        let wide: Vec<u16> = narrow.iter().map(|&c| u16::from(c) * 257).collect();
        let (t8, t16) = (Texture::new(&narrow, 2, 2), Texture::new(&wide, 2, 2));
        for (u, v) in [(1.0, 0.5), (0.7, 1.3), (1.0, 1.0), (0.5, 0.5), (1.5, 1.5)] {
            let (a, b) = (t8.sample(u, v), t16.sample(u, v));
            for k in 0..4 {
                let widened = i32::from(a[k]) * 257;
                assert!(
                    (widened - i32::from(b[k])).abs() <= 257,
                    "({u}, {v}): {a:?} vs {b:?}"
                );
            }
        }
        // Exactly between two 16-bit values the result keeps the precision 8 bits lack.
        let fine: [u16; 8] = [1000, 2000, 3000, 65535, 1001, 2001, 3001, 65535];
        let t = Texture::new(&fine, 2, 1);
        assert_eq!(t.sample(1.0, 0.5), [1001, 2001, 3001, 65535]);
        assert_eq!(t.sample(1.5, 0.5), [1001, 2001, 3001, 65535]);
    }

    #[test]
    fn transparent_regions_keep_their_colour() {
        let data: [u8; 8] = [200, 100, 0, 0, 100, 50, 0, 0];
        let t = Texture::new(&data, 2, 1);
        assert_eq!(t.sample(1.0, 0.5), [150, 75, 0, 0]);
    }
}
