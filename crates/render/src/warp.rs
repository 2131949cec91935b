//! The CPU warp: draw a deformed textured mesh into a new image.

use image::RgbaImage;
use rayon::iter::ParallelExtend;

use crate::raster::Raster;
use crate::sample::{FIXED_RANGE, Texel, Texture, step_to_fixed, to_fixed};
use crate::{Picture, RenderError, Rgba16Image, WarpMesh};

/// Options for [`warp_cpu`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RasterOptions {
    /// RGBA colour of output pixels that no triangle covers
    /// (default: transparent black `[0, 0, 0, 0]`).
    pub background: [u8; 4],
}

/// Allocates a zeroed buffer of `width × height × channels` elements, or
/// reports that it cannot.
fn alloc<T: Clone + Default + Send>(
    width: u32,
    height: u32,
    channels: u64,
) -> Result<Vec<T>, RenderError> {
    let too_large = || RenderError::OutputTooLarge { width, height };
    let len = u64::from(width)
        .checked_mul(u64::from(height))
        .and_then(|n| n.checked_mul(channels))
        .and_then(|n| usize::try_from(n).ok())
        .filter(|&n| n <= isize::MAX as usize / std::mem::size_of::<T>().max(1))
        .ok_or_else(too_large)?;
    let mut buffer = Vec::new();
    buffer.try_reserve_exact(len).map_err(|_| too_large())?;
    // Zero (and fault in) the pages on all threads.
    buffer.par_extend(rayon::iter::repeat_n(T::default(), len));
    Ok(buffer)
}

/// Draws `mesh` into a new `width × height` RGBA image, on the CPU.
///
/// Each triangle is drawn at its `deformed` positions. An output pixel belongs
/// to a triangle when its centre `(x + 0.5, y + 0.5)` lies inside it; centres
/// exactly on an edge follow the top-left rule, so a mesh without overlaps
/// draws every covered pixel exactly once, with no gaps along shared edges.
/// Vertex positions are snapped to 1/256 pixel for this test and clamped to
/// ±2²⁰ pixels.
///
/// A covered pixel takes the texture's value at the `rest` position
/// interpolated (affinely, i.e. barycentrically) from the triangle's vertices,
/// filtered bilinearly in premultiplied alpha and clamped to the texture edge.
/// Positions within 10⁻⁴ texel of a texel centre read that texel exactly, so
/// `deformed == rest` over the whole image reproduces `texture` byte for byte.
/// There is no mipmapping: strong minification aliases.
///
/// * Fold-overs (triangles whose deformed winding is flipped) are drawn like
///   any other triangle.
/// * Where triangles overlap, **the later triangle in `mesh.triangles` is in
///   front**: its sample is composited over what is there ([`crate::over`],
///   straight alpha), so a half-transparent edge of the part in front shows the part
///   behind through it rather than a crack. A pixel drawn once gets its sample
///   exactly.
/// * Triangles of zero area after snapping are skipped, as are (absurd)
///   triangles whose texture mapping overflows `f64`.
/// * Pixels no triangle covers get `opts.background` (the background is not under
///   the drawn pixels: it fills what nothing covers).
///
/// Work is split into bands of rows drawn in parallel on the rayon pool.
///
/// # Errors
/// * the errors of [`WarpMesh::validate`];
/// * [`RenderError::EmptyTexture`] if `texture` has no pixels;
/// * [`RenderError::OutputTooLarge`] if the output cannot be allocated.
///
/// # Example
/// ```
/// use glam::Vec2;
/// use render::{warp_cpu, RasterOptions, WarpMesh};
///
/// let texture = image::RgbaImage::from_pixel(4, 4, image::Rgba([200, 10, 10, 255]));
/// // One quad over the whole texture, drawn shifted right by one pixel.
/// let rest = [Vec2::new(0.0, 0.0), Vec2::new(4.0, 0.0), Vec2::new(4.0, 4.0), Vec2::new(0.0, 4.0)];
/// let deformed = rest.map(|p| p + Vec2::X);
/// let mesh = WarpMesh { rest: &rest, deformed: &deformed, triangles: &[[0, 1, 2], [0, 2, 3]] };
/// let out = warp_cpu(&texture, &mesh, 4, 4, &RasterOptions::default())?;
/// assert_eq!(out.get_pixel(0, 0).0, [0, 0, 0, 0]);
/// assert_eq!(out.get_pixel(1, 0).0, [200, 10, 10, 255]);
/// # Ok::<(), render::RenderError>(())
/// ```
pub fn warp_cpu(
    texture: &RgbaImage,
    mesh: &WarpMesh,
    width: u32,
    height: u32,
    opts: &RasterOptions,
) -> Result<RgbaImage, RenderError> {
    let (tw, th) = texture.dimensions();
    let pixels = warp_texels(
        texture.as_raw(),
        tw,
        th,
        mesh,
        width,
        height,
        opts.background,
    )?;
    RgbaImage::from_raw(width, height, pixels).ok_or(RenderError::OutputTooLarge { width, height })
}

/// Draws `mesh` textured with `texture` as [`warp_cpu`] does, in the picture's own
/// depth: a 16-bit picture is sampled and written with 16 bits per channel (the
/// background's channels widened by ×257), an 8-bit one exactly as [`warp_cpu`]
/// draws it.
///
/// # Errors
/// As [`warp_cpu`].
pub fn warp_picture(
    texture: &Picture,
    mesh: &WarpMesh,
    width: u32,
    height: u32,
    opts: &RasterOptions,
) -> Result<Picture, RenderError> {
    match texture {
        Picture::Rgba8(texture) => warp_cpu(texture, mesh, width, height, opts).map(Picture::Rgba8),
        Picture::Rgba16(texture) => {
            let (tw, th) = texture.dimensions();
            let background = opts.background.map(|c| u16::from(c) * 257);
            let pixels = warp_texels(texture.as_raw(), tw, th, mesh, width, height, background)?;
            Rgba16Image::from_raw(width, height, pixels)
                .map(Picture::Rgba16)
                .ok_or(RenderError::OutputTooLarge { width, height })
        }
    }
}

/// Draws `mesh` textured with `texture` over `target` (8 bits per channel, any size),
/// as [`warp_cpu`] draws it over transparent pixels: each covered pixel takes the
/// sample composited over what `target` holds ([`crate::over`]), so where `target` is
/// transparent it takes the sample exactly, and pixels no triangle covers keep their
/// value. Used to put a warped layer over a picture without losing what lies under
/// its transparent parts.
///
/// # Errors
/// As [`warp_cpu`] (without the allocation).
pub fn warp_over(
    texture: &RgbaImage,
    mesh: &WarpMesh,
    target: &mut RgbaImage,
) -> Result<(), RenderError> {
    let (tw, th) = texture.dimensions();
    check(mesh, tw, th)?;
    let (width, height) = target.dimensions();
    draw_texels(texture.as_raw(), tw, th, mesh, target, width, height);
    Ok(())
}

/// As [`warp_over`], in the picture's own depth: `texture` and `target` must have the
/// same depth (a 16-bit picture is drawn over a 16-bit target with 16 bits per
/// channel).
///
/// # Errors
/// As [`warp_over`], and [`RenderError::DepthMismatch`] for pictures of different
/// depths.
pub fn warp_picture_over(
    texture: &Picture,
    mesh: &WarpMesh,
    target: &mut Picture,
) -> Result<(), RenderError> {
    let (tw, th) = texture.dimensions();
    check(mesh, tw, th)?;
    let (width, height) = target.dimensions();
    match (texture, target) {
        (Picture::Rgba8(texture), Picture::Rgba8(target)) => {
            draw_texels(texture.as_raw(), tw, th, mesh, target, width, height);
        }
        (Picture::Rgba16(texture), Picture::Rgba16(target)) => {
            draw_texels(texture.as_raw(), tw, th, mesh, target, width, height);
        }
        (texture, target) => {
            return Err(RenderError::DepthMismatch {
                texture: texture.bits_per_channel(),
                target: target.bits_per_channel(),
            });
        }
    }
    Ok(())
}

/// Makes transparent every pixel of `picture` that `mesh` covers at its deformed
/// positions, by the rasteriser's own rule (pixel centres, top-left fill rule): the
/// pixels [`warp_picture_over`] would draw. Drawing the same mesh over the cleared
/// picture at rest gives the picture back exactly.
///
/// # Errors
/// An invalid mesh, or a picture too large to count coverage for.
pub fn clear_covered(picture: &mut Picture, mesh: &WarpMesh) -> Result<(), RenderError> {
    let (w, h) = picture.dimensions();
    let covered = coverage_counts(mesh, w, h)?;
    match picture {
        Picture::Rgba8(image) => clear_where(image.pixels_mut().map(|p| &mut p.0), &covered),
        Picture::Rgba16(image) => clear_where(image.pixels_mut().map(|p| &mut p.0), &covered),
    }
    Ok(())
}

/// Sets to transparent black each pixel whose count is positive.
fn clear_where<'a, C: Default + Copy + 'a>(
    pixels: impl Iterator<Item = &'a mut [C; 4]>,
    counts: &[u32],
) {
    for (pixel, &count) in pixels.zip(counts) {
        if count > 0 {
            *pixel = [C::default(); 4];
        }
    }
}

/// Refuses an invalid mesh or an empty texture.
fn check(mesh: &WarpMesh, tw: u32, th: u32) -> Result<(), RenderError> {
    mesh.validate()?;
    if tw == 0 || th == 0 {
        return Err(RenderError::EmptyTexture {
            width: tw,
            height: th,
        });
    }
    Ok(())
}

/// The work of [`warp_cpu`] on row-major RGBA texels of either depth.
fn warp_texels<C: Texel>(
    texels: &[C],
    tw: u32,
    th: u32,
    mesh: &WarpMesh,
    width: u32,
    height: u32,
    background: [C; 4],
) -> Result<Vec<C>, RenderError> {
    check(mesh, tw, th)?;
    let mut pixels = alloc::<C>(width, height, 4)?;
    draw_texels(texels, tw, th, mesh, &mut pixels, width, height);
    if background != [C::default(); 4] {
        // What no triangle covers takes the background (a second scan, for coverage
        // alone: a background other than transparent is rare).
        let mut covered = alloc::<u8>(width, height, 1)?;
        Raster::new(mesh, width, height).scan(
            &mut covered,
            1,
            |_| {},
            |_, _, columns, row| row[columns.start as usize..columns.end as usize].fill(1),
        );
        for (px, &drawn) in pixels.chunks_exact_mut(4).zip(&covered) {
            if drawn == 0 {
                px.copy_from_slice(&background);
            }
        }
    }
    Ok(pixels)
}

/// Draws a checked `mesh` over `pixels` (row-major RGBA, `width × height`), each
/// sample composited over what the pixel holds.
fn draw_texels<C: Texel>(
    texels: &[C],
    tw: u32,
    th: u32,
    mesh: &WarpMesh,
    pixels: &mut [C],
    width: u32,
    height: u32,
) {
    let raster = Raster::new(mesh, width, height);
    let texture = Texture::new(texels, tw, th);
    // Each sample goes over what the pixel holds: a pixel drawn once over a
    // transparent one takes its sample exactly.
    let put = |px: &mut [C], sample: [C; 4]| {
        let base = [px[0], px[1], px[2], px[3]];
        px.copy_from_slice(&C::over(sample, base));
    };
    raster.scan(
        pixels,
        4,
        |_| {},
        |setup, y, columns, row| {
            let map = &setup.map;
            let [u0, v0] = map.row_start(f64::from(y) + 0.5);
            let [du_dx, dv_dx] = map.du;
            let at = |x: u32| {
                let xc = f64::from(x) + 0.5;
                (u0 + du_dx * xc, v0 + dv_dx * xc)
            };
            let out = &mut row[columns.start as usize * 4..columns.end as usize * 4];
            let (first, last) = (at(columns.start), at(columns.end - 1));
            let in_range = |(u, v): (f64, f64)| u.abs() < FIXED_RANGE && v.abs() < FIXED_RANGE;
            if in_range(first) && in_range(last) {
                // Step in exact fixed point along the span (rounding the step
                // costs under 2^-33 texel per pixel). Every sampled position
                // lies between `first` and `last`; only the unused step after
                // the last pixel may overflow, hence the wrapping adds.
                let (mut u, mut v) = (to_fixed(first.0), to_fixed(first.1));
                let (du, dv) = (step_to_fixed(du_dx), step_to_fixed(dv_dx));
                for px in out.chunks_exact_mut(4) {
                    put(px, texture.sample_fixed(u, v));
                    u = u.wrapping_add(du);
                    v = v.wrapping_add(dv);
                }
            } else {
                for (px, x) in out.chunks_exact_mut(4).zip(columns) {
                    let (u, v) = at(x);
                    put(px, texture.sample_fixed(to_fixed(u), to_fixed(v)));
                }
            }
        },
    );
}

/// How many triangles of `mesh` cover each pixel of a `width × height`
/// output, row-major (`y * width + x`), using exactly the coverage rule of
/// [`warp_cpu`].
///
/// Useful to test watertightness (every count is 1 for a mesh that tiles the
/// image) and to show fold-overs (counts above 1).
///
/// # Errors
/// As [`warp_cpu`], except that no texture is involved.
pub fn coverage_counts(mesh: &WarpMesh, width: u32, height: u32) -> Result<Vec<u32>, RenderError> {
    mesh.validate()?;
    let mut counts = alloc::<u32>(width, height, 1)?;
    Raster::new(mesh, width, height).scan(
        &mut counts,
        1,
        |_| {},
        |_, _, columns, row| {
            for c in &mut row[columns.start as usize..columns.end as usize] {
                *c = c.saturating_add(1);
            }
        },
    );
    Ok(counts)
}
