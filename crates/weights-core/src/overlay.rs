//! Handles placed over a posed rig ("overlaid"): a departure from the paper for
//! insertions in a posed state, so that placing a handle moves nothing.
//!
//! The paper's Algorithm 1 re-partitions the neighbourhood of a new handle, and its
//! refinement cascades: every node whose nearest neighbour comes closer gets a smaller
//! support, so weights change far from the new handle (a pin by the lizard's head
//! moves its tail by 40 px). An overlaid handle does not join the partition. Each of
//! its samples `s` has the paper's support rule, r_s = the distance to the nearest node
//! (of the partition, of its own other samples, or of an overlaid handle placed before
//! it), and a bump b_s = φ(d_s / r_s); the handle's share is β = 1 − Π (1 − b_s) (one
//! bump for a point handle, their union for a bar's samples), and it takes that share
//! from every weight
//! under it: w ← (1 − β)·w, then its samples get β·b_s / Σ b. Overlaid handles apply in
//! handle order.
//!
//! What that keeps: the weights still sum to one, are non-negative, C² where φ is, and
//! one at each handle's own samples (a bump reaches no other node, and later bumps do
//! not reach earlier handles' samples); outside the bumps nothing changes.
//!
//! **How an overlaid handle moves the picture.** Not by its own transform applied to
//! the rest shape (a similarity cannot follow a pose's stretch and bend over the
//! bump: that left 4–18 px on the lizard), but by how far it is from where the
//! picture under it puts it: F, the similarity that best fits the picture beneath
//! (the partition's, and the overlaid handles' before it) — through the picture's
//! place of the handle's rest point, turned and scaled by the least-squares fit over
//! the vertices within its distance to the nearest node, weighted by φ (for a bar:
//! the similarity taking its rest ends to where the picture has them) — and
//! R = T ∘ F⁻¹ moves the picture under the bump: P ← (1 − β)·P + β·R(P). The editor
//! gives a handle placed in a posed state (and its pose in every key) exactly that
//! fit ([`similarity_fit`]), so R is the identity there and nothing moves; dragged,
//! turned or scaled afterwards, it moves the picture under it as a handle does, and
//! its point stays under it whatever the other handles do.

use std::collections::HashMap;

use geometry::Similarity;
use glam::{DAffine2, DVec2};

use crate::basis::Basis;
use crate::domain::{Domain, Metric};
use crate::error::RigError;
use crate::rig::{Handle, Node, NodeKind};
use crate::weights::{ball, nearest_node_distance};

/// The overlaid handles' nodes and bumps.
#[derive(Clone, Debug, Default)]
pub(crate) struct Overlay {
    /// The overlaid handles' samples, in handle order.
    pub nodes: Vec<Node>,
    /// Support radius of each of `nodes`.
    pub radii: Vec<f64>,
    /// For each sample a bump reaches: (index into `nodes`, b) in ascending order.
    bumps: HashMap<u32, Vec<(u32, f64)>>,
    /// Per overlaid handle (in order): how its fit F is found, and the samples its
    /// bump reaches with β.
    layers: Vec<Layer>,
}

/// One overlaid handle.
#[derive(Clone, Debug, PartialEq)]
struct Layer {
    handle: usize,
    /// The samples the bump reaches, with the handle's share β there.
    share: Vec<(u32, f64)>,
    anchor: Anchor,
}

/// Where the fit F of an overlaid handle is taken from.
#[derive(Clone, Debug, PartialEq)]
enum Anchor {
    /// A point handle: its rest point's place (a triangle's corners and barycentric
    /// coordinates), and the vertices of the fit with their weights.
    Point {
        rest: DVec2,
        at: Option<([u32; 3], [f64; 3])>,
        fit: Vec<(u32, f64)>,
    },
    /// A bar: its rest ends' places.
    Bar {
        rest: [DVec2; 2],
        at: [Option<([u32; 3], [f64; 3])>; 2],
    },
}

impl Overlay {
    /// The bumps of `samples` (each overlaid handle's nodes, in handle order) over a
    /// partition with nodes on `base` samples.
    ///
    /// # Errors
    /// A sample on a real node's sample (virtual nodes on the same sample are passed
    /// over: the handle takes their place).
    pub fn build(
        domain: &Domain,
        basis: &Basis,
        handles: &[Handle],
        base: &[Node],
        samples: Vec<Node>,
    ) -> Result<Self, RigError> {
        let positions = domain.positions();
        let mut is_node = crate::weights::SampleSet::new(domain.len());
        let mut owner: HashMap<u32, usize> = HashMap::new();
        let mut points: Vec<DVec2> = Vec::new();
        for n in base {
            is_node.insert(n.vertex);
            if let Some(h) = handle_of(n) {
                owner.insert(n.vertex, h);
            }
            points.push(positions[n.vertex as usize]);
        }
        let mut overlay = Self {
            nodes: Vec::with_capacity(samples.len()),
            radii: Vec::with_capacity(samples.len()),
            bumps: HashMap::new(),
            layers: Vec::new(),
        };
        let mut start = 0;
        while start < samples.len() {
            let handle = handle_of(&samples[start]);
            let end = start
                + samples[start..]
                    .iter()
                    .take_while(|n| handle_of(n) == handle)
                    .count();
            let own = &samples[start..end];
            for n in own {
                if let Some(&a) = owner.get(&n.vertex) {
                    return Err(RigError::SameSample {
                        a,
                        b: handle.unwrap_or(usize::MAX),
                    });
                }
            }
            let mine = |v: u32| own.iter().any(|n| n.vertex == v);
            let first = overlay.nodes.len();
            // The fit's anchor, from the nodes there are before this handle's.
            let place = |p: DVec2| {
                domain
                    .locate(p)
                    .map(|(t, bary)| (domain.triangles()[t], bary))
            };
            let anchor = match handle.and_then(|h| handles.get(h)) {
                Some(Handle::Bar { rest, .. }) => Anchor::Bar {
                    rest: *rest,
                    at: rest.map(place),
                },
                Some(Handle::Point { rest, .. }) => {
                    let reach = points
                        .iter()
                        .map(|q| q.distance(*rest))
                        .fold(f64::INFINITY, f64::min);
                    Anchor::Point {
                        rest: *rest,
                        at: place(*rest),
                        fit: fit_weights(domain, basis, *rest, reach),
                    }
                }
                None => Anchor::Point {
                    rest: DVec2::ZERO,
                    at: None,
                    fit: Vec::new(),
                },
            };
            for n in own {
                let radius = match domain.metric() {
                    Metric::Intrinsic => {
                        nearest_node_distance(domain, n.vertex, &|v| is_node.contains(v) || mine(v))
                    }
                    Metric::Euclidean => {
                        let p = positions[n.vertex as usize];
                        points
                            .iter()
                            .chain(own.iter().map(|m| &positions[m.vertex as usize]))
                            .map(|q| q.distance(p))
                            .filter(|&d| d > 0.0)
                            .fold(f64::INFINITY, f64::min)
                    }
                };
                let k = overlay.nodes.len() as u32;
                for (v, d) in ball(domain, n.vertex, radius) {
                    let b = if radius.is_finite() {
                        basis.eval(d / radius)
                    } else {
                        1.0
                    };
                    if b > 0.0 {
                        overlay.bumps.entry(v).or_default().push((k, b));
                    }
                }
                overlay.nodes.push(*n);
                overlay.radii.push(radius);
            }
            let mut share: HashMap<u32, (f64, f64)> = HashMap::new();
            for (&v, bumps) in &overlay.bumps {
                for &(k, b) in bumps {
                    if k as usize >= first {
                        share.entry(v).or_insert((1.0, 0.0)).0 *= 1.0 - b;
                    }
                }
            }
            let mut share: Vec<(u32, f64)> = share
                .into_iter()
                .map(|(v, (keep, _))| (v, 1.0 - keep))
                .collect();
            share.sort_unstable_by_key(|e| e.0);
            overlay.layers.push(Layer {
                handle: handle.unwrap_or(usize::MAX),
                share,
                anchor,
            });
            for n in own {
                is_node.insert(n.vertex);
                owner.insert(n.vertex, handle.unwrap_or(usize::MAX));
                points.push(positions[n.vertex as usize]);
            }
            start = end;
        }
        Ok(overlay)
    }

    /// Whether a bump reaches sample `v`.
    pub fn touches(&self, v: u32) -> bool {
        self.bumps.contains_key(&v)
    }

    /// Lays the overlay over `row` (sample `v`'s weights over the partition's nodes),
    /// numbering its nodes from `first`.
    pub fn apply(&self, v: u32, row: &mut Vec<(usize, f64)>, first: usize) {
        let Some(bumps) = self.bumps.get(&v) else {
            return;
        };
        let mut i = 0;
        while i < bumps.len() {
            let handle = handle_of(&self.nodes[bumps[i].0 as usize]);
            let group = bumps[i..]
                .iter()
                .take_while(|(k, _)| handle_of(&self.nodes[*k as usize]) == handle)
                .count();
            let group = &bumps[i..i + group];
            let keep: f64 = group.iter().map(|(_, b)| 1.0 - b).product();
            let sum: f64 = group.iter().map(|(_, b)| b).sum();
            let share = 1.0 - keep;
            for e in row.iter_mut() {
                e.1 *= keep;
            }
            row.retain(|e| e.1 > 0.0);
            row.extend(
                group
                    .iter()
                    .map(|&(k, b)| (first + k as usize, share * b / sum)),
            );
            i += group.len();
        }
    }

    /// Whether any handle is overlaid.
    pub fn is_empty(&self) -> bool {
        self.layers.is_empty()
    }

    /// Moves `picture` (the partition's, posed) as the overlaid handles of `handles`
    /// move it, in order (see the module's docs).
    pub fn pose(&self, handles: &[Handle], positions: &[DVec2], picture: &mut [DVec2]) {
        let at = |picture: &[DVec2], place: &Option<([u32; 3], [f64; 3])>| {
            place.map(|(tri, bary)| (0..3).map(|i| picture[tri[i] as usize] * bary[i]).sum())
        };
        for layer in &self.layers {
            let Some(handle) = handles.get(layer.handle) else {
                continue;
            };
            let fitted = match &layer.anchor {
                Anchor::Point {
                    rest,
                    at: place,
                    fit,
                } => at(picture, place).map(|p: DVec2| {
                    let (a, b) = similarity_terms(positions, picture, fit, *rest, p);
                    let linear = glam::DMat2::from_cols(DVec2::new(a, b), DVec2::new(-b, a));
                    DAffine2::from_mat2_translation(linear, p - linear * *rest)
                }),
                Anchor::Bar { rest, at: places } => {
                    match (at(picture, &places[0]), at(picture, &places[1])) {
                        (Some(a), Some(b)) if a != b => {
                            let c = (rest[0] + rest[1]) * 0.5;
                            Some(Similarity::from_segments(c, *rest, [a, b]).to_affine(c))
                        }
                        _ => None,
                    }
                }
            };
            let own = handle_affine(handle);
            // R = T ∘ F⁻¹; a fit folded flat moves the picture by the handle's
            // displacement alone.
            let moved = match fitted.filter(|f| f.matrix2.determinant().abs() > 1e-12) {
                Some(f) => own * f.inverse(),
                None => {
                    let c = anchor_point(&layer.anchor);
                    let from = match &layer.anchor {
                        Anchor::Point { at: place, .. } => at(picture, place),
                        Anchor::Bar { .. } => None,
                    };
                    DAffine2::from_translation(own.transform_point2(c) - from.unwrap_or(c))
                }
            };
            for &(v, beta) in &layer.share {
                let p = picture[v as usize];
                picture[v as usize] = p + beta * (moved.transform_point2(p) - p);
            }
        }
    }

    /// Whether two overlays are the same, bump for bump.
    pub fn same_as(&self, other: &Self) -> bool {
        self.nodes == other.nodes
            && self.radii == other.radii
            && self.bumps == other.bumps
            && self.layers == other.layers
    }
}

/// The handle a node belongs to.
fn handle_of(n: &Node) -> Option<usize> {
    match n.kind {
        NodeKind::Point { handle } | NodeKind::BarSample { handle, .. } => Some(handle),
        NodeKind::Boundary | NodeKind::Virtual => None,
    }
}

/// The rest point a layer is anchored at.
fn anchor_point(anchor: &Anchor) -> DVec2 {
    match anchor {
        Anchor::Point { rest, .. } => *rest,
        Anchor::Bar { rest, .. } => (rest[0] + rest[1]) * 0.5,
    }
}

/// A handle's own map, in image coordinates.
fn handle_affine(handle: &Handle) -> DAffine2 {
    match *handle {
        Handle::Point { rest, transform } => transform.to_affine(rest),
        Handle::Bar { rest, pose } => {
            let c = (rest[0] + rest[1]) * 0.5;
            Similarity::from_segments(c, rest, pose).to_affine(c)
        }
    }
}

/// The vertices a similarity is fitted over at `rest`: those within `reach` (straight
/// line), each weighted by φ(d / reach). Empty when `reach` is not finite.
fn fit_weights(domain: &Domain, basis: &Basis, rest: DVec2, reach: f64) -> Vec<(u32, f64)> {
    if !reach.is_finite() {
        return Vec::new();
    }
    let positions = domain.positions();
    domain
        .vertices_near_segment(rest, rest, reach)
        .into_iter()
        .map(|v| (v, basis.eval(positions[v as usize].distance(rest) / reach)))
        .collect()
}

/// The least-squares similarity taking the `fit` vertices' rest places about `rest`
/// to their `picture` places about `at`: its linear part as (a, b) = (s cos θ, s sin θ).
fn similarity_terms(
    positions: &[DVec2],
    picture: &[DVec2],
    fit: &[(u32, f64)],
    rest: DVec2,
    at: DVec2,
) -> (f64, f64) {
    let (mut dot, mut cross, mut norm) = (0.0, 0.0, 0.0);
    for &(v, w) in fit {
        let (Some(p), Some(q)) = (positions.get(v as usize), picture.get(v as usize)) else {
            continue;
        };
        let d = *p - rest;
        let e = *q - at;
        dot += w * d.dot(e);
        cross += w * d.perp_dot(e);
        norm += w * d.length_squared();
    }
    if norm > 0.0 && dot.is_finite() && cross.is_finite() {
        (dot / norm, cross / norm)
    } else {
        (1.0, 0.0)
    }
}

/// The similarity a point handle placed at `rest` in a posed state gets, so that it
/// moves nothing: the least-squares fit of `picture` (a place per sample of `domain`)
/// about `at`, the picture's place of `rest`, over the samples within `reach` of it
/// (its distance to the nearest node), each weighted by φ(d / reach). Returns the
/// rotation (radians) and scale; `None` where nothing is there to fit or the picture
/// is folded flat. The rig fits overlaid handles the same way (see [`crate::Rig`]).
pub fn similarity_fit(
    domain: &Domain,
    basis: &Basis,
    picture: &[DVec2],
    rest: DVec2,
    at: DVec2,
    reach: f64,
) -> Option<(f64, f64)> {
    let fit = fit_weights(domain, basis, rest, reach);
    if fit.is_empty() {
        return None;
    }
    let (a, b) = similarity_terms(domain.positions(), picture, &fit, rest, at);
    let scale = a.hypot(b);
    (scale > 1e-6 && scale.is_finite()).then(|| (b.atan2(a), scale))
}
