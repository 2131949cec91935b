//! Layered artwork warped as parts: every visible layer meshed along its own outline
//! and deformed by the handles that bind it, then composited in the layers' order
//! (`c2warp render --parts`).
//!
//! A handle binds every visible layer with a visible pixel under it (for a bar: under
//! both ends and its middle), so a handle placed where two layers overlap — a shoulder,
//! a hip — binds both: a joint. Each part is set up by the project's method on its own
//! layer alone, with the handles that bind it, so distances stay inside the part; the
//! rig's density is shared among the parts by visible area. A part that no handle
//! binds stays where it is. Hidden layers are kept as they are.
//!
//! Not yet: a part that no handle binds following the part beneath it, parts in the
//! editor, automatic depth between parts (the ARAP paper's §5.1), LBC cages over
//! parts.

use anyhow::{Context, Result, bail};
use glam::DVec2;
use project::{Canvas, Controls, HandleSpec, Hold, Project};
use render::Picture;

use crate::{DEFAULT_DENSITY, Frame, Listener, placed, prepare_warper, warp_picture};

/// The fewest vertices a part is meshed with, whatever its share of the density.
const MIN_PART_DENSITY: usize = 200;

/// What [`warp_parts`] made.
pub struct Parts {
    /// The layers warped, each on the whole canvas at the origin (hidden layers as
    /// they were), in the artwork's order.
    pub warped: layers::Artwork,
    /// For each layer, the handles (indices into the project's) that bind it; empty
    /// for a hidden layer.
    pub bindings: Vec<Vec<usize>>,
}

/// Warps each visible layer of `artwork` as a part by `project`'s handles (see the
/// module documentation); `density` (else the project's, else the default) is the
/// total over the parts. The canvas is kept (the artwork's).
///
/// # Errors
/// An LBC project (its cage deforms the picture as a whole), a handle bound to no
/// part (off every visible layer), or what setting up or warping a part fails with,
/// naming the layer.
pub fn warp_parts(
    artwork: &layers::Artwork,
    project: &Project,
    density: Option<usize>,
    listener: &dyn Listener,
) -> Result<Parts> {
    if project.method.controls() == Controls::Cage {
        bail!("a cage (LBC) deforms the picture as a whole: render it without parts");
    }
    let canvas = Frame {
        origin: [0, 0],
        width: artwork.width,
        height: artwork.height,
    };
    let bindings: Vec<Vec<usize>> = artwork
        .layers
        .iter()
        .map(|layer| {
            if !layer.visible {
                return Vec::new();
            }
            (0..project.handles.len())
                .filter(|&h| {
                    probes(&project.handles[h])
                        .iter()
                        .all(|p| covers(layer, *p))
                })
                .collect()
        })
        .collect();
    if let Some(h) = (0..project.handles.len()).find(|h| !bindings.iter().any(|b| b.contains(h))) {
        bail!(
            "handle {} lies on no visible layer: place it on a part",
            h + 1
        );
    }
    let areas: Vec<u64> = artwork
        .layers
        .iter()
        .map(|l| {
            if l.visible {
                visible_pixels(&l.pixels)
            } else {
                0
            }
        })
        .collect();
    let total_area = areas.iter().sum::<u64>().max(1);
    let total = density.or(project.density).unwrap_or(DEFAULT_DENSITY);
    let mut warped = Vec::with_capacity(artwork.layers.len());
    for ((layer, bound), &area) in artwork.layers.iter().zip(&bindings).zip(&areas) {
        let pixels = if !layer.visible {
            layer.pixels.clone()
        } else {
            let on_canvas = placed(
                &layer.pixels,
                canvas,
                [i64::from(layer.x), i64::from(layer.y)],
            )?;
            if bound.is_empty() {
                on_canvas
            } else {
                let share = (total as u128 * u128::from(area) / u128::from(total_area)) as usize;
                let part = part_project(project, bound);
                let warper = prepare_warper(
                    &on_canvas.to_rgba8(),
                    &part,
                    Some(share.max(MIN_PART_DENSITY)),
                    listener,
                )
                .with_context(|| format!("part \"{}\"", layer.name))?;
                warp_picture(&on_canvas, &warper)
                    .with_context(|| format!("part \"{}\"", layer.name))?
            }
        };
        let (x, y) = if layer.visible {
            (0, 0)
        } else {
            (layer.x, layer.y)
        };
        warped.push(layers::Layer {
            name: layer.name.clone(),
            x,
            y,
            opacity: layer.opacity,
            visible: layer.visible,
            pixels,
        });
    }
    Ok(Parts {
        warped: layers::Artwork {
            width: artwork.width,
            height: artwork.height,
            layers: warped,
            notes: Vec::new(),
        },
        bindings,
    })
}

/// `project` with the handles `bound` alone (their holds and overlay kept, renumbered),
/// no animation, on the canvas as it is.
fn part_project(project: &Project, bound: &[usize]) -> Project {
    let index = |h: usize| bound.iter().position(|&b| b == h);
    let mut part = project.clone();
    part.handles = bound.iter().map(|&h| project.handles[h].clone()).collect();
    part.overlaid = project.overlaid.iter().filter_map(|&h| index(h)).collect();
    part.holds = project
        .holds
        .iter()
        .filter_map(|hold| {
            index(hold.handle).map(|handle| Hold {
                handle,
                ..hold.clone()
            })
        })
        .collect();
    part.animation = None;
    part.canvas = Canvas::Keep;
    part
}

/// The rest points a layer must cover for a handle to bind it: a point's place; a
/// bar's ends and middle.
fn probes(handle: &HandleSpec) -> Vec<DVec2> {
    match handle {
        HandleSpec::Point { rest, .. } => vec![DVec2::from(*rest)],
        HandleSpec::Bar { rest, .. } => {
            let (a, b) = (DVec2::from(rest[0]), DVec2::from(rest[1]));
            vec![a, (a + b) / 2.0, b]
        }
    }
}

/// Whether `layer` has a visible pixel (alpha > 0) at canvas point `p`.
fn covers(layer: &layers::Layer, p: DVec2) -> bool {
    let (x, y) = (
        p.x.floor() - f64::from(layer.x),
        p.y.floor() - f64::from(layer.y),
    );
    let (w, h) = layer.dimensions();
    if !(x >= 0.0 && y >= 0.0 && x < f64::from(w) && y < f64::from(h)) {
        return false;
    }
    alpha(&layer.pixels, x as u32, y as u32) > 0
}

fn alpha(picture: &Picture, x: u32, y: u32) -> u16 {
    match picture {
        Picture::Rgba8(im) => u16::from(im.get_pixel(x, y)[3]),
        Picture::Rgba16(im) => im.get_pixel(x, y)[3],
    }
}

/// The number of pixels with alpha > 0.
fn visible_pixels(picture: &Picture) -> u64 {
    let (w, h) = picture.dimensions();
    let mut n = 0;
    for y in 0..h {
        for x in 0..w {
            n += u64::from(alpha(picture, x, y) > 0);
        }
    }
    n
}
