//! Bilinear texture sampling in premultiplied alpha.

/// Sampling positions closer than this (in texels) to a texel centre are
/// snapped onto it, so that an identity map reproduces texels exactly despite
/// floating-point rounding.
pub(crate) const SNAP_TEXELS: f64 = 1e-4;

/// A borrowed RGBA8 texture with clamp-to-edge bilinear sampling.
pub(crate) struct Texture<'a> {
    data: &'a [u8],
    width: usize,
    max_x: f64,
    max_y: f64,
}

impl<'a> Texture<'a> {
    /// Wraps `data` (row-major RGBA8, `width × height`, both non-zero).
    pub(crate) fn new(data: &'a [u8], width: u32, height: u32) -> Self {
        Self {
            data,
            width: width as usize,
            max_x: f64::from(width.saturating_sub(1)),
            max_y: f64::from(height.saturating_sub(1)),
        }
    }

    #[inline]
    fn texel(&self, x: usize, y: usize) -> [u8; 4] {
        let i = (y * self.width + x) * 4;
        match self.data.get(i..i + 4) {
            Some(&[r, g, b, a]) => [r, g, b, a],
            _ => [0; 4],
        }
    }

    /// Samples at texture position `(u, v)` in source pixels (texel `(i, j)`
    /// has its centre at `(i + 0.5, j + 0.5)`).
    ///
    /// Colours are premultiplied by alpha before filtering and divided by the
    /// filtered alpha afterwards, so a transparent neighbour contributes
    /// coverage but no colour (no dark fringes on cut-outs).
    #[inline]
    pub(crate) fn sample(&self, u: f64, v: f64) -> [u8; 4] {
        let (x0, x1, fx) = axis(u, self.max_x);
        let (y0, y1, fy) = axis(v, self.max_y);
        if fx == 0.0 && fy == 0.0 {
            return self.texel(x0, y0);
        }
        let (fx, fy) = (fx as f32, fy as f32);
        let taps = [
            (self.texel(x0, y0), (1.0 - fx) * (1.0 - fy)),
            (self.texel(x1, y0), fx * (1.0 - fy)),
            (self.texel(x0, y1), (1.0 - fx) * fy),
            (self.texel(x1, y1), fx * fy),
        ];
        blend(&taps)
    }
}

/// Splits one texture coordinate into the two texel indices to blend and the
/// weight of the second.
#[inline]
fn axis(coordinate: f64, max: f64) -> (usize, usize, f64) {
    let mut s = coordinate - 0.5;
    let nearest = s.round();
    if (s - nearest).abs() < SNAP_TEXELS {
        s = nearest;
    }
    let s = s.clamp(0.0, max);
    let i0 = s.floor();
    let frac = s - i0;
    let i0 = i0 as usize;
    let i1 = if frac > 0.0 { i0 + 1 } else { i0 };
    (i0, i1, frac)
}

/// Weighted premultiplied average of texels; weights sum to one.
#[inline]
fn blend(taps: &[([u8; 4], f32); 4]) -> [u8; 4] {
    let mut alpha = 0.0f32;
    let mut premultiplied = [0.0f32; 3];
    for &(texel, weight) in taps {
        let wa = weight * f32::from(texel[3]);
        alpha += wa;
        for (acc, &c) in premultiplied.iter_mut().zip(&texel[..3]) {
            *acc += wa * f32::from(c);
        }
    }
    let to_u8 = |v: f32| (v + 0.5).clamp(0.0, 255.0) as u8;
    if alpha > 0.0 {
        let [r, g, b] = premultiplied.map(|c| to_u8(c / alpha));
        [r, g, b, to_u8(alpha)]
    } else {
        // Fully transparent: keep the (straight) filtered colour under it.
        let mut straight = [0.0f32; 3];
        for &(texel, weight) in taps {
            for (acc, &c) in straight.iter_mut().zip(&texel[..3]) {
                *acc += weight * f32::from(c);
            }
        }
        let [r, g, b] = straight.map(to_u8);
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
        let data = [10, 20, 30, 40, 50, 60, 70, 80];
        let t = Texture::new(&data, 2, 1);
        assert_eq!(t.sample(-100.0, 0.5), [10, 20, 30, 40]);
        assert_eq!(t.sample(100.0, -7.0), [50, 60, 70, 80]);
        // Must not panic; the value is unspecified.
        let _ = t.sample(f64::NAN, f64::INFINITY);
    }

    #[test]
    fn premultiplied_half_way_has_no_dark_fringe() {
        let data = [255, 0, 0, 255, 0, 0, 0, 0];
        let t = Texture::new(&data, 2, 1);
        assert_eq!(t.sample(1.0, 0.5), [255, 0, 0, 128]);
    }

    #[test]
    fn transparent_regions_keep_their_colour() {
        let data = [200, 100, 0, 0, 100, 50, 0, 0];
        let t = Texture::new(&data, 2, 1);
        assert_eq!(t.sample(1.0, 0.5), [150, 75, 0, 0]);
    }
}
