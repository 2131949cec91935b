//! Porter–Duff "over" in straight (not premultiplied) alpha, exact where it can be.
//!
//! Where the warped picture overlaps itself, the part in front is composited over the
//! part behind: its anti-aliased edge lets what is behind show through, instead of
//! punching a half-transparent crack into it. The sum is worked in premultiplied form
//! and divided back, rounded to nearest; three cases are exact by construction, so a
//! picture drawn over nothing comes back texel for texel:
//! - an opaque top, or a top over a fully transparent base, gives the top as it is
//!   (its colour kept even where it is transparent);
//! - a fully transparent top leaves the base as it is.

/// `top` over `base`, 8 bits per channel, straight alpha.
///
/// ```
/// // Half-covered red over opaque blue: opaque, half way between.
/// assert_eq!(render::over([255, 0, 0, 128], [0, 0, 255, 255]), [128, 0, 127, 255]);
/// // Over nothing, the top comes back as it is.
/// assert_eq!(render::over([10, 20, 30, 40], [0, 0, 0, 0]), [10, 20, 30, 40]);
/// ```
#[inline]
pub fn over(top: [u8; 4], base: [u8; 4]) -> [u8; 4] {
    let (ta, ba) = (u64::from(top[3]), u64::from(base[3]));
    if ta == 255 || ba == 0 {
        return top;
    }
    if ta == 0 {
        return base;
    }
    // In units of 1/255²: the top's coverage and what the base adds under it.
    let (wt, wb) = (ta * 255, ba * (255 - ta));
    let a = wt + wb;
    let mut out = [0u8; 4];
    for c in 0..3 {
        let sum = wt * u64::from(top[c]) + wb * u64::from(base[c]);
        out[c] = ((sum + a / 2) / a).min(255) as u8;
    }
    out[3] = ((a + 127) / 255).min(255) as u8;
    out
}

/// `top` over `base`, 16 bits per channel, straight alpha (as [`over`]).
#[inline]
pub fn over16(top: [u16; 4], base: [u16; 4]) -> [u16; 4] {
    const MAX: u64 = u16::MAX as u64;
    let (ta, ba) = (u64::from(top[3]), u64::from(base[3]));
    if ta == MAX || ba == 0 {
        return top;
    }
    if ta == 0 {
        return base;
    }
    // Units of 1/65535² (< 2^32); the products below stay under 2^49.
    let (wt, wb) = (ta * MAX, ba * (MAX - ta));
    let a = wt + wb;
    let mut out = [0u16; 4];
    for c in 0..3 {
        let sum = wt * u64::from(top[c]) + wb * u64::from(base[c]);
        out[c] = ((sum + a / 2) / a).min(MAX) as u16;
    }
    out[3] = ((a + MAX / 2) / MAX).min(MAX) as u16;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_exact_cases_are_exact() {
        for top in [[1, 2, 3, 0], [9, 8, 7, 1], [200, 100, 50, 255]] {
            assert_eq!(over(top, [0, 0, 0, 0]), top);
            assert_eq!(over(top, [5, 5, 5, 0]), top);
        }
        assert_eq!(over([1, 2, 3, 255], [9, 9, 9, 77]), [1, 2, 3, 255]);
        assert_eq!(over([1, 2, 3, 0], [9, 9, 9, 77]), [9, 9, 9, 77]);
        assert_eq!(over16([1, 2, 3, 0], [0, 0, 0, 0]), [1, 2, 3, 0]);
        assert_eq!(over16([1, 2, 3, 65535], [9, 9, 9, 9]), [1, 2, 3, 65535]);
        assert_eq!(over16([1, 2, 3, 0], [9, 9, 9, 9]), [9, 9, 9, 9]);
    }

    #[test]
    fn anything_over_an_opaque_base_is_opaque() {
        for ta in 0..=255u8 {
            let out = over([250, 10, 0, ta], [0, 20, 250, 255]);
            assert_eq!(out[3], 255, "top alpha {ta}");
            // The colour moves from the base's to the top's with the top's alpha.
            let expected = (250.0 * f64::from(ta) / 255.0).round();
            assert!(
                (f64::from(out[0]) - expected).abs() <= 0.5001,
                "{ta}: {out:?}"
            );
        }
        let out = over16([65535, 0, 0, 32768], [0, 0, 65535, 65535]);
        assert_eq!(out[3], 65535);
        assert_eq!(out[0], 32768);
        assert_eq!(out[2], 32767);
    }

    #[test]
    fn alpha_adds_up_as_porter_and_duff_have_it() {
        for (ta, ba) in [(128u8, 128u8), (1, 254), (254, 1), (77, 200)] {
            let out = over([0, 0, 0, ta], [0, 0, 0, ba]);
            let (t, b) = (f64::from(ta) / 255.0, f64::from(ba) / 255.0);
            let expected = (t + b * (1.0 - t)) * 255.0;
            assert!(
                (f64::from(out[3]) - expected).abs() <= 0.5001,
                "{ta} over {ba}"
            );
            // Two half-covered layers never lose coverage: the result covers at
            // least as much as either.
            assert!(out[3] >= ta.max(ba));
        }
    }

    #[test]
    fn sixteen_bits_agree_with_eight() {
        for (top, base) in [
            ([255u8, 0, 0, 128u8], [0u8, 0, 255, 255u8]),
            ([10, 200, 30, 60], [90, 80, 70, 140]),
        ] {
            let wide = |p: [u8; 4]| p.map(|c| u16::from(c) * 257);
            let (a, b) = (over(top, base), over16(wide(top), wide(base)));
            for k in 0..4 {
                assert!((i32::from(a[k]) * 257 - i32::from(b[k])).abs() <= 257);
            }
        }
    }
}
