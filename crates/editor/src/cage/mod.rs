//! The cage tool (LBC, Zhang et al. 2014): draw a closed polygon around the subject
//! (or start from the picture's outline), adjust its vertices at rest, solve its local
//! barycentric coordinates on the worker, then drag a vertex or a box-selected group to
//! warp what lies inside the cage; what lies outside stays as it is.
//!
//! The tool has three states, read from the document rather than stored:
//! - **drawing** — a polygon being clicked ([`CageTool::draft`]), or no cage yet;
//! - **rest** — the rig file has a cage whose coordinates are not solved (or the user
//!   chose to edit it at rest): drags move rest vertices, a click on an edge inserts a
//!   vertex, Alt-click or Delete removes one, Enter solves;
//! - **posed** — the cage is solved: drags move the posed vertices (a selected group
//!   together), a drag on empty canvas selects by box.
//!
//! The overlays of a solved cage live here too: the support contour of the selected
//! vertex's coordinate function at `10⁻³/n` (its heat map is the GPU's), and the panel
//! with the paper's locality statistics `P(t)` and `Q(k)` as plots.
//!
//! [`CageTool`] owns all of the tool's state and sees the editor through
//! [`Host`]: its input and keys are in `input`, its edits of the cage in `edits`, what
//! it draws over the canvas in `paint`, its side panel and the locality plots in
//! `panel`.

mod edits;
mod input;
mod paint;
mod panel;

use std::sync::Arc;

use egui::{Color32, Context, Pos2, Response, Ui};
use glam::DVec2;
use project::{Controls, Project};

use crate::document::Document;
use crate::tool::{CanvasTool, Host};
use crate::viewport::Viewport;

/// How close the pointer must be to grab a cage vertex or edge, screen points.
const GRAB: f32 = 9.0;
/// Half the side of a cage vertex's square, screen points.
const VERTEX: f32 = 4.5;

const CAGE: Color32 = Color32::from_rgb(120, 230, 255);
const CAGE_REST: Color32 = Color32::from_rgba_premultiplied(150, 150, 150, 150);
const CROSSING: Color32 = Color32::from_rgb(255, 60, 60);
const SELECTED: Color32 = Color32::from_rgb(255, 212, 0);
const OUTLINE: Color32 = Color32::from_rgb(20, 20, 20);
const CONTOUR: Color32 = Color32::from_rgb(80, 255, 160);

/// A point on a mesh edge: `(a, b, t)` is `a + t·(b − a)`.
pub type EdgePoint = (u32, u32, f64);

/// A level-set segment between two points on mesh edges.
pub type ContourSegment = [EdgePoint; 2];

/// A support contour, by the (cage vertex, weights version) it was traced for.
type CachedContour = ((usize, u64), Arc<Vec<ContourSegment>>);

/// What a primary click or drag with the cage tool does now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CageState {
    /// Clicking a new polygon.
    Drawing,
    /// Adjusting the cage at rest before it is solved.
    Rest,
    /// Posing the solved cage.
    Posed,
}

/// A drag of cage vertices in progress.
#[derive(Clone, Debug)]
struct CageDrag {
    /// The vertices moved, each with where it was when the drag began.
    vertices: Vec<(usize, DVec2)>,
    /// Rest vertices (else posed ones).
    rest: bool,
    /// The pointer when the drag began (image pixels).
    pointer: DVec2,
    /// The cage's vertex count when the drag began.
    count: usize,
    /// The document before the drag, recorded in the history if the drag changed it.
    before: Project,
}

/// The cage tool: its settings, the polygon being drawn, the selection, the gesture
/// under way and the support contour it last traced (none of it is saved: the cage
/// itself is in the rig file).
#[derive(Clone, Debug)]
pub struct CageTool {
    /// The polygon being drawn, image pixels.
    draft: Option<Vec<DVec2>>,
    /// Selected cage vertices; the last one's coordinate function is the heat map.
    selected: Vec<usize>,
    drag: Option<CageDrag>,
    /// A box selection being dragged: where it started and where the pointer is
    /// (image pixels), and whether it adds to the selection (Shift).
    boxing: Option<(DVec2, DVec2, bool)>,
    /// Edit the solved cage at rest instead of posing it.
    edit_rest: bool,
    /// How many vertices "Cage from outline" makes.
    pub outline_vertices: usize,
    /// Mesh vertices inside a new cage, unless the project names a count (the side
    /// panel changes it per cage): the solve's time grows quickly with it.
    pub inside_vertices: usize,
    /// The "Vertices inside" slider's value while it is dragged.
    density_draft: Option<usize>,
    /// The support contour of the heat map's vertex, by (vertex, weights version):
    /// segments between points on mesh edges `(a, b, t)`, `t` from `a` to `b`.
    contour: Option<CachedContour>,
}

impl Default for CageTool {
    fn default() -> Self {
        Self {
            draft: None,
            selected: Vec::new(),
            drag: None,
            boxing: None,
            edit_rest: false,
            outline_vertices: 16,
            inside_vertices: pipeline::cage::DEFAULT_CAGE_VERTICES,
            density_draft: None,
            contour: None,
        }
    }
}

impl CageTool {
    /// What the tool does now in `doc`.
    pub fn state(&self, doc: Option<&Document>) -> CageState {
        if self.draft.is_some() {
            return CageState::Drawing;
        }
        match doc {
            Some(doc) if doc.method().controls() == Controls::Cage && doc.cage().is_some() => {
                if doc.cage_solution().is_some() && !self.edit_rest {
                    CageState::Posed
                } else {
                    CageState::Rest
                }
            }
            _ => CageState::Drawing,
        }
    }

    /// The selected vertex whose coordinate function the heat map shows.
    pub fn focus(&self) -> Option<usize> {
        self.selected.last().copied()
    }

    /// The selection (cage vertex indices; the last is the heat map's).
    pub fn selection(&self) -> &[usize] {
        &self.selected
    }

    /// The polygon being drawn, if any (image pixels).
    pub fn draft(&self) -> Option<&[DVec2]> {
        self.draft.as_deref()
    }

    /// Whether a drag of vertices or a box selection is under way.
    pub fn gesture_under_way(&self) -> bool {
        self.drag.is_some() || self.boxing.is_some()
    }

    /// Whether a solved cage warps the view of `doc`: LBC with its cage solved, and no
    /// new polygon being drawn (that is drawn over the picture at rest).
    pub fn warping(&self, doc: Option<&Document>) -> bool {
        self.draft.is_none() && doc.is_some_and(Document::cage_warps)
    }

    /// Forgets selected vertices a cage of `count` vertices does not have.
    pub(crate) fn retain_valid(&mut self, count: usize) {
        self.selected.retain(|&i| i < count);
    }

    /// Forgets all the tool held of the document (the polygon being drawn, the
    /// selection, a gesture, the traced contour) and keeps its settings: for a newly
    /// opened document.
    pub(crate) fn forget_document(&mut self) {
        *self = Self {
            outline_vertices: self.outline_vertices,
            inside_vertices: self.inside_vertices,
            ..Self::default()
        };
    }

    /// The tool's invariants in `doc`: its selection and drag name vertices the cage
    /// has, a vertex is selected at most once, and the polygon being drawn is finite.
    ///
    /// # Errors
    /// The first broken invariant, in words.
    pub(crate) fn sanity_check(&self, doc: &Document) -> anyhow::Result<()> {
        let count = doc.cage().map_or(0, |c| c.rest.len());
        if let Some(&i) = self.selected.iter().find(|&&i| i >= count) {
            anyhow::bail!("cage vertex {i} is selected, but the cage has {count}");
        }
        let mut seen = self.selected.clone();
        seen.sort_unstable();
        seen.dedup();
        if seen.len() != self.selected.len() {
            anyhow::bail!("a cage vertex is selected twice");
        }
        if let Some(drag) = &self.drag
            && (drag.count != count || drag.vertices.iter().any(|&(i, _)| i >= count))
        {
            anyhow::bail!("a drag holds cage vertices the cage of {count} does not have");
        }
        if let Some(draft) = &self.draft
            && draft.iter().any(|p| !p.is_finite())
        {
            anyhow::bail!("a cage being drawn has a non-finite vertex");
        }
        Ok(())
    }

    /// The cage's vertices as the tool shows them in `doc`: rest positions while
    /// drawing or editing at rest, posed ones when posing.
    fn shown(&self, doc: Option<&Document>) -> Vec<DVec2> {
        let Some(doc) = doc else {
            return Vec::new();
        };
        match self.state(Some(doc)) {
            CageState::Posed => doc.cage_pose(),
            CageState::Rest => doc.cage_rest(),
            CageState::Drawing => Vec::new(),
        }
    }
}

impl CanvasTool for CageTool {
    /// Draws, adjusts or poses the cage as its state calls for (see the module's
    /// documentation); pan with the middle button or Space is the canvas's.
    fn input(&mut self, host: &mut dyn Host, ui: &Ui, response: &Response) {
        self.pointer_input(host, ui, response);
    }

    /// The cage (and the polygon being drawn, a box selection, the support contour),
    /// whether or not the tool is in use: the canvas paints it whenever it shows the
    /// cage's view.
    fn paint(
        &mut self,
        host: &mut dyn Host,
        painter: &egui::Painter,
        pointer: Option<Pos2>,
        _active: bool,
    ) {
        self.paint_cage(host, painter, pointer);
    }

    /// What the tool does now, its buttons, τ and the density inside the cage.
    fn panel(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        ui.separator();
        ui.heading("Cage");
        self.cage_panel(host, ui);
    }

    /// Enter closes the polygon or solves, Backspace / Delete remove the last drawn or
    /// the selected vertices, Escape drops the polygon being drawn or the selection,
    /// N / Shift+N step through the vertices.
    fn keys(&mut self, host: &mut dyn Host, ctx: &Context) {
        self.key_input(host, ctx);
    }

    /// Drops the polygon being drawn and a box selection. A drag of vertices has
    /// changed the document already: [`CageTool::finish_gesture`] ends it, as an
    /// undo step.
    fn cancel(&mut self) {
        self.draft = None;
        self.boxing = None;
    }
}

/// The vertex of `points` under screen point `pos`.
fn vertex_at(viewport: &Viewport, points: &[DVec2], pos: Pos2) -> Option<usize> {
    points
        .iter()
        .enumerate()
        .map(|(i, &p)| (i, viewport.to_screen(p).distance(pos)))
        .filter(|&(_, d)| d < GRAB)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// The edge of the closed polygon `points` under screen point `pos`, and where on it
/// (image pixels).
fn edge_at(viewport: &Viewport, points: &[DVec2], pos: Pos2) -> Option<(usize, DVec2)> {
    let n = points.len();
    (0..n)
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % n]);
            let (sa, sb) = (viewport.to_screen(a), viewport.to_screen(b));
            let (d, t) = segment_distance(pos, sa, sb);
            (i, d, a + (b - a) * f64::from(t))
        })
        .filter(|&(_, d, _)| d < GRAB)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _, p)| (i, p))
}

/// `p` moved into `doc`'s picture (cage vertices lie on it).
fn on_image(doc: Option<&Document>, p: DVec2) -> DVec2 {
    let Some(doc) = doc else { return p };
    let size = DVec2::new(f64::from(doc.image.width()), f64::from(doc.image.height()));
    p.clamp(DVec2::ZERO, size)
}

/// The segments of the level set `value = level` of the piecewise-linear function with
/// `values` at the vertices of `triangles` (marching triangles): each as two points
/// on mesh edges, `(a, b, t)` meaning `a + t·(b − a)`.
pub fn contour(triangles: &[[u32; 3]], values: &[f32], level: f32) -> Vec<ContourSegment> {
    let mut out = Vec::new();
    for tri in triangles {
        let Some(v) = tri
            .iter()
            .map(|&k| values.get(k as usize).copied())
            .collect::<Option<Vec<f32>>>()
        else {
            continue;
        };
        let mut crossings = Vec::with_capacity(2);
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            let (a, b) = (v[i] - level, v[j] - level);
            if (a < 0.0) != (b < 0.0) {
                let t = f64::from(a / (a - b));
                crossings.push((tri[i], tri[j], t));
            }
        }
        if let [p, q] = crossings[..] {
            out.push([p, q]);
        }
    }
    out
}

/// The pairs of edges of the closed polygon `points` that cross or touch (other than
/// neighbours at their shared vertex).
pub fn crossing_edges(points: &[DVec2]) -> Vec<(usize, usize)> {
    let n = points.len();
    let mut out = Vec::new();
    if n < 4 {
        return out;
    }
    let orient = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    for i in 0..n {
        let (a, b) = (points[i], points[(i + 1) % n]);
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let (c, d) = (points[j], points[(j + 1) % n]);
            let (o1, o2) = (orient(a, b, c), orient(a, b, d));
            let (o3, o4) = (orient(c, d, a), orient(c, d, b));
            if o1 * o2 <= 0.0 && o3 * o4 <= 0.0 && (o1 != 0.0 || o2 != 0.0 || o3 != 0.0) {
                out.push((i, j));
            }
        }
    }
    out
}

fn segment_distance(p: Pos2, a: Pos2, b: Pos2) -> (f32, f32) {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_sq().max(1e-9)).clamp(0.0, 1.0);
    (p.distance(a + ab * t), t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_contour_of_a_linear_ramp_is_a_straight_line() {
        // Two triangles over the unit square, values x.
        let triangles = [[0, 1, 2], [0, 2, 3]];
        let values = [0.0, 1.0, 1.0, 0.0];
        let segments = contour(&triangles, &values, 0.25);
        assert_eq!(segments.len(), 2);
        let positions = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        for segment in segments {
            for (a, b, t) in segment {
                let p = positions[a as usize].lerp(positions[b as usize], t);
                assert!((p.x - 0.25).abs() < 1e-6, "{p}");
            }
        }
        // A level no vertex straddles: nothing.
        assert!(contour(&triangles, &values, 2.0).is_empty());
    }

    #[test]
    fn crossings_are_found_and_neighbours_are_not() {
        let square = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        assert!(crossing_edges(&square).is_empty());
        // A bow tie: edges 1 and 3 cross in the middle.
        let bow = [square[0], square[1], square[3], square[2]];
        assert_eq!(crossing_edges(&bow), vec![(1, 3)]);
    }
}
