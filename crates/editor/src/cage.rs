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

use std::sync::Arc;

use egui::{Color32, Key, Modifiers, PointerButton, Pos2, Rect, Shape, Stroke, StrokeKind, Ui};
use glam::DVec2;
use project::{Method, Project, Tau};

use crate::app::{EditorApp, Tool};
use crate::document::{CageKey, Edit};

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
pub(crate) struct CageDrag {
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

impl CageDrag {
    /// The cage's vertex count when the drag began.
    pub(crate) fn count(&self) -> usize {
        self.count
    }

    /// The vertices being dragged.
    pub(crate) fn vertices(&self) -> impl Iterator<Item = usize> + '_ {
        self.vertices.iter().map(|&(i, _)| i)
    }
}

/// The cage tool's state in the editor (none of it is saved: the cage itself is in the
/// rig file).
#[derive(Clone, Debug)]
pub struct CageTool {
    /// The polygon being drawn, image pixels.
    pub(crate) draft: Option<Vec<DVec2>>,
    /// Selected cage vertices; the last one's coordinate function is the heat map.
    pub(crate) selected: Vec<usize>,
    pub(crate) drag: Option<CageDrag>,
    /// A box selection being dragged: where it started and where the pointer is
    /// (image pixels), and whether it adds to the selection (Shift).
    pub(crate) boxing: Option<(DVec2, DVec2, bool)>,
    /// Edit the solved cage at rest instead of posing it.
    pub(crate) edit_rest: bool,
    /// How many vertices "Cage from outline" makes.
    pub outline_vertices: usize,
    /// The "Vertices inside" slider's value while it is dragged.
    pub(crate) density_draft: Option<usize>,
    /// The support contour of the heat map's vertex, by (vertex, weights version):
    /// segments between points on mesh edges `(a, b, t)`, `t` from `a` to `b`.
    pub(crate) contour: Option<CachedContour>,
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
            density_draft: None,
            contour: None,
        }
    }
}

impl CageTool {
    /// The selected vertex whose coordinate function the heat map shows.
    pub fn focus(&self) -> Option<usize> {
        self.selected.last().copied()
    }

    /// Forgets selected vertices a cage of `count` vertices does not have.
    pub(crate) fn retain_valid(&mut self, count: usize) {
        self.selected.retain(|&i| i < count);
    }
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

impl EditorApp {
    /// What the cage tool does now.
    pub fn cage_state(&self) -> CageState {
        if self.cage.draft.is_some() {
            return CageState::Drawing;
        }
        match &self.doc {
            Some(doc) if doc.method() == Method::Lbc && doc.cage().is_some() => {
                if doc.cage_solution().is_some() && !self.cage.edit_rest {
                    CageState::Posed
                } else {
                    CageState::Rest
                }
            }
            _ => CageState::Drawing,
        }
    }

    /// The cage tool's selection (cage vertex indices; the last is the heat map's).
    pub fn cage_selection(&self) -> &[usize] {
        &self.cage.selected
    }

    /// The polygon being drawn, if any (image pixels).
    pub fn cage_draft(&self) -> Option<&[DVec2]> {
        self.cage.draft.as_deref()
    }

    /// Whether the canvas shows the picture as the cage tool sees it (at rest, with a
    /// solved cage's inside warped) rather than warped by handles.
    pub(crate) fn cage_view(&self) -> bool {
        self.tool == Tool::Cage || self.doc.as_ref().is_some_and(|d| d.method() == Method::Lbc)
    }

    /// Whether a solved cage warps the view: LBC with its cage solved, and no new
    /// polygon being drawn (that is drawn over the picture at rest).
    pub(crate) fn cage_warping(&self) -> bool {
        self.cage.draft.is_none() && self.doc.as_ref().is_some_and(|d| d.cage_warps())
    }

    /// The cage's vertices as the tool shows them: rest positions while drawing or
    /// editing at rest, posed ones when posing.
    fn shown_cage(&self) -> Vec<DVec2> {
        let Some(doc) = &self.doc else {
            return Vec::new();
        };
        match self.cage_state() {
            CageState::Posed => doc.cage_pose(),
            CageState::Rest => doc.cage_rest(),
            CageState::Drawing => Vec::new(),
        }
    }

    /// The vertex of `points` under screen point `pos`.
    fn cage_vertex_at(&self, points: &[DVec2], pos: Pos2) -> Option<usize> {
        points
            .iter()
            .enumerate()
            .map(|(i, &p)| (i, self.viewport.to_screen(p).distance(pos)))
            .filter(|&(_, d)| d < GRAB)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    /// The edge of the closed polygon `points` under screen point `pos`, and where on
    /// it (image pixels).
    fn cage_edge_at(&self, points: &[DVec2], pos: Pos2) -> Option<(usize, DVec2)> {
        let n = points.len();
        (0..n)
            .map(|i| {
                let (a, b) = (points[i], points[(i + 1) % n]);
                let (sa, sb) = (self.viewport.to_screen(a), self.viewport.to_screen(b));
                let (d, t) = segment_distance(pos, sa, sb);
                (i, d, a + (b - a) * f64::from(t))
            })
            .filter(|&(_, d, _)| d < GRAB)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _, p)| (i, p))
    }

    /// `p` moved into the picture (cage vertices lie on it).
    fn on_image(&self, p: DVec2) -> DVec2 {
        let Some(doc) = &self.doc else { return p };
        let size = DVec2::new(f64::from(doc.image.width()), f64::from(doc.image.height()));
        p.clamp(DVec2::ZERO, size)
    }

    /// The cage tool's pointer input (pan with the middle button or Space is the
    /// canvas's).
    pub(crate) fn cage_input(&mut self, ui: &Ui, response: &egui::Response) {
        let (modifiers, space) = ui.input(|i| (i.modifiers, i.key_down(Key::Space)));
        let press = ui
            .input(|i| i.pointer.press_origin())
            .or(response.interact_pointer_pos());
        let state = self.cage_state();
        if response.drag_started_by(PointerButton::Primary)
            && !space
            && let Some(pos) = press
        {
            self.start_cage_drag(state, pos, modifiers);
        }
        if response.dragged()
            && !self.panning
            && let Some(pos) = response.interact_pointer_pos()
        {
            let at = self.viewport.to_image(pos);
            if self.cage.drag.is_some() {
                self.cage_drag_to(at);
            } else if let Some((_, end, _)) = &mut self.cage.boxing {
                *end = at;
            }
        }
        if response.drag_stopped() {
            self.finish_cage_gesture();
        }
        if response.double_clicked_by(PointerButton::Primary) && state == CageState::Drawing {
            if self.cage.draft.as_ref().is_some_and(|d| d.len() >= 3) {
                self.close_cage();
            }
        } else if response.clicked_by(PointerButton::Primary)
            && let Some(pos) = response.interact_pointer_pos()
        {
            self.cage_click(state, pos, modifiers);
        }
        let hovering_vertex = response
            .hover_pos()
            .is_some_and(|p| self.cage_vertex_at(&self.shown_cage(), p).is_some());
        let cursor = if self.cage.drag.is_some() {
            Some(egui::CursorIcon::Grabbing)
        } else if hovering_vertex {
            Some(egui::CursorIcon::Grab)
        } else if response.hovered() {
            Some(egui::CursorIcon::Crosshair)
        } else {
            None
        };
        if let Some(cursor) = cursor {
            ui.ctx().set_cursor_icon(cursor);
        }
    }

    fn start_cage_drag(&mut self, state: CageState, pos: Pos2, modifiers: Modifiers) {
        let Some(doc) = &self.doc else { return };
        if state == CageState::Drawing {
            // Dragging while drawing pans, as with the Puppet tool.
            self.panning = true;
            return;
        }
        let points = self.shown_cage();
        let at = self.viewport.to_image(pos);
        match self.cage_vertex_at(&points, pos) {
            Some(v) => {
                if !self.cage.selected.contains(&v) {
                    if !modifiers.shift {
                        self.cage.selected.clear();
                    }
                    self.cage.selected.push(v);
                } else {
                    // The grabbed vertex shows its heat map.
                    self.cage.selected.retain(|&i| i != v);
                    self.cage.selected.push(v);
                }
                let vertices = self
                    .cage
                    .selected
                    .iter()
                    .filter_map(|&i| Some((i, *points.get(i)?)))
                    .collect();
                self.cage.drag = Some(CageDrag {
                    vertices,
                    rest: state == CageState::Rest,
                    pointer: at,
                    count: points.len(),
                    before: doc.snapshot(),
                });
            }
            None => self.cage.boxing = Some((at, at, modifiers.shift)),
        }
    }

    /// Moves the dragged vertices so the grabbed one follows the pointer.
    fn cage_drag_to(&mut self, pointer: DVec2) {
        let Some(drag) = &self.cage.drag else { return };
        let Some(doc) = &self.doc else { return };
        let mut points = if drag.rest {
            doc.cage_rest()
        } else {
            doc.cage_pose()
        };
        if points.len() != drag.count {
            debug_assert!(false, "the cage changed under a drag");
            return;
        }
        let delta = pointer - drag.pointer;
        let rest = drag.rest;
        for &(i, start) in &drag.vertices {
            points[i] = if rest {
                self.on_image(start + delta)
            } else {
                start + delta
            };
        }
        self.set_cage_points(rest, &points);
    }

    /// Sets the cage's rest vertices (the pose goes back to rest) or its pose, without
    /// an undo step (the gesture makes one when it ends).
    fn set_cage_points(&mut self, rest: bool, points: &[DVec2]) {
        let Some(doc) = &mut self.doc else { return };
        let mut project = doc.project().clone();
        let Some(cage) = &mut project.cage else {
            return;
        };
        let points: Vec<[f64; 2]> = points.iter().map(|p| p.to_array()).collect();
        if rest {
            cage.rest = points;
            cage.pose = None;
        } else {
            cage.pose = (points != cage.rest).then_some(points);
        }
        if let Err(e) = doc.restore(project) {
            self.error(&e);
        }
    }

    /// Ends a drag of cage vertices (one undo step if it changed anything) or a box
    /// selection (selecting the vertices inside the box).
    pub(crate) fn finish_cage_gesture(&mut self) {
        if let Some(drag) = self.cage.drag.take()
            && let Some(doc) = &self.doc
            && doc.project() != &crate::app::without_virtuals(&drag.before)
        {
            self.history.push(drag.before);
            self.dirty = true;
        }
        if let Some((a, b, add)) = self.cage.boxing.take() {
            let (lo, hi) = (a.min(b), a.max(b));
            let inside: Vec<usize> = self
                .shown_cage()
                .iter()
                .enumerate()
                .filter(|(_, p)| p.cmpge(lo).all() && p.cmple(hi).all())
                .map(|(i, _)| i)
                .collect();
            if !add {
                self.cage.selected.clear();
            }
            for i in inside {
                if !self.cage.selected.contains(&i) {
                    self.cage.selected.push(i);
                }
            }
        }
    }

    fn cage_click(&mut self, state: CageState, pos: Pos2, modifiers: Modifiers) {
        let at = self.on_image(self.viewport.to_image(pos));
        match state {
            CageState::Drawing => {
                let viewport = self.viewport;
                let near = |p: &DVec2| viewport.to_screen(*p).distance(pos) < GRAB;
                let draft = self.cage.draft.get_or_insert_with(Vec::new);
                if draft.len() >= 3 && draft.first().is_some_and(near) {
                    self.close_cage();
                } else if !draft.iter().any(near) {
                    // A click on a vertex already drawn adds none on top of it.
                    draft.push(at);
                }
            }
            CageState::Rest | CageState::Posed => {
                let points = self.shown_cage();
                if let Some(v) = self.cage_vertex_at(&points, pos) {
                    if modifiers.alt && state == CageState::Rest {
                        self.cage.selected = vec![v];
                        self.delete_cage_vertices();
                    } else if modifiers.shift && self.cage.selected.contains(&v) {
                        self.cage.selected.retain(|&i| i != v);
                    } else {
                        if !modifiers.shift {
                            self.cage.selected.clear();
                        }
                        self.cage.selected.retain(|&i| i != v);
                        self.cage.selected.push(v);
                    }
                } else if state == CageState::Rest
                    && let Some((edge, p)) = self.cage_edge_at(&points, pos)
                {
                    let mut rest = points;
                    rest.insert(edge + 1, self.on_image(p));
                    if self.set_cage_rest(rest) {
                        self.cage.selected = vec![edge + 1];
                    }
                } else if !modifiers.shift {
                    self.cage.selected.clear();
                }
            }
        }
    }

    /// Replaces the rest cage (one undo step; the pose goes back to rest and the
    /// cage must be solved again).
    fn set_cage_rest(&mut self, rest: Vec<DVec2>) -> bool {
        let rest = rest.iter().map(|p| p.to_array()).collect();
        let vertices = self.cage_vertices;
        self.edit(Edit::Cage { rest, vertices })
    }

    /// Closes the polygon being drawn into the rig file's cage (LBC becomes the
    /// method). A polygon that is not simple is refused, and stays to be fixed.
    pub fn close_cage(&mut self) {
        let Some(draft) = self.cage.draft.take() else {
            return;
        };
        if draft.len() < 3 {
            self.error(&anyhow::anyhow!(
                "a cage needs at least 3 vertices: click around the subject"
            ));
            self.cage.draft = Some(draft);
            return;
        }
        if let Err(e) = lbc::Cage::new(draft.clone()) {
            self.error(&anyhow::anyhow!(
                "the cage was not closed: {e} (Backspace removes the last vertex)"
            ));
            self.cage.draft = Some(draft);
            return;
        }
        let n = draft.len();
        if self.set_cage_rest(draft.clone()) {
            self.cage.selected.clear();
            self.cage.edit_rest = false;
            self.info(format!(
                "a cage of {n} vertices: drag its vertices to adjust it (click an edge to \
                 add one, Alt-click to remove one), then Solve (Enter)"
            ));
        } else {
            self.cage.draft = Some(draft);
        }
    }

    /// Removes the selected cage vertices (at rest; at least three stay).
    pub fn delete_cage_vertices(&mut self) {
        let Some(doc) = &self.doc else { return };
        if self.cage.selected.is_empty() {
            return;
        }
        if self.cage_state() == CageState::Posed {
            self.error(&anyhow::anyhow!(
                "vertices are removed at rest: choose Edit the rest cage first"
            ));
            return;
        }
        let rest = doc.cage_rest();
        let left: Vec<DVec2> = rest
            .iter()
            .enumerate()
            .filter(|(i, _)| !self.cage.selected.contains(i))
            .map(|(_, p)| *p)
            .collect();
        if left.len() < 3 {
            self.error(&anyhow::anyhow!("a cage keeps at least 3 vertices"));
            return;
        }
        let removed = rest.len() - left.len();
        if self.set_cage_rest(left) {
            self.cage.selected.clear();
            self.info(format!("removed {removed} cage vertices"));
        }
    }

    /// Solves the cage's coordinates on the worker (Escape cancels); then a drag
    /// poses it.
    pub fn solve_cage(&mut self) {
        let Some(key) = self.doc.as_ref().and_then(|d| CageKey::of(d.project())) else {
            self.error(&anyhow::anyhow!(
                "there is no cage to solve: draw one first"
            ));
            return;
        };
        if self
            .doc
            .as_ref()
            .is_some_and(|d| d.solution_for(&key).is_some())
        {
            self.cage.edit_rest = false;
            return;
        }
        self.cage.edit_rest = false;
        self.start_cage_solve(key, None);
    }

    /// A cage around the picture's visible shape, with as many vertices as the panel
    /// asks (one undo step).
    pub fn cage_from_outline(&mut self) {
        let Some(doc) = &self.doc else { return };
        let (w, h) = doc.image.dimensions();
        let offset = pipeline::cage::outline_offset(w, h);
        let vertices = self.cage.outline_vertices;
        match pipeline::cage::cage_from_outline(&doc.image, vertices, offset) {
            Ok(ring) => {
                self.cage.draft = None;
                let note = pipeline::cage::outline_note(vertices, ring.len())
                    .map_or(String::new(), |n| format!(" ({n})"));
                let count = ring.len();
                if self.set_cage_rest(ring) {
                    self.cage.selected.clear();
                    self.cage.edit_rest = false;
                    self.info(format!(
                        "a cage of {count} vertices around everything visible{note}: adjust \
                         it, then Solve (Enter)"
                    ));
                }
            }
            Err(e) => self.error(&e.context("no cage from the outline")),
        }
    }

    /// Removes the cage (one undo step; LBC gives way to C²).
    pub fn clear_cage(&mut self) {
        self.cage.draft = None;
        if self.doc.as_ref().is_some_and(|d| d.cage().is_some()) && self.edit(Edit::ClearCage) {
            self.cage.selected.clear();
            self.cage.edit_rest = false;
            self.info("the cage is gone: click to draw a new one");
        }
    }

    /// Puts the cage's vertices back at rest (one undo step).
    pub fn reset_cage_pose(&mut self) {
        let Some(doc) = &self.doc else { return };
        let Some(cage) = doc.cage() else { return };
        if cage.pose.is_some() {
            let rest = cage.rest.clone();
            let _ = self.edit(Edit::CagePose(rest));
        }
    }

    /// Edits the solved cage at rest (its pose goes back to rest first), or poses it
    /// again.
    pub fn toggle_cage_rest(&mut self) {
        if self.cage.edit_rest {
            self.cage.edit_rest = false;
            if self.cage_state() == CageState::Rest {
                self.solve_cage();
            }
            return;
        }
        self.reset_cage_pose();
        self.cage.edit_rest = true;
    }

    /// The cage tool's keys: Enter closes the polygon or solves, Backspace / Delete
    /// remove the last drawn or the selected vertices, Escape drops the polygon being
    /// drawn or the selection, N / Shift+N step through the vertices.
    pub(crate) fn cage_keys(&mut self, ctx: &egui::Context) {
        let pressed = |modifiers, key| {
            ctx.input_mut(|i| i.consume_shortcut(&egui::KeyboardShortcut::new(modifiers, key)))
        };
        let none = Modifiers::NONE;
        let state = self.cage_state();
        if pressed(none, Key::Enter) {
            match state {
                CageState::Drawing => self.close_cage(),
                CageState::Rest => self.solve_cage(),
                CageState::Posed => {}
            }
        }
        if pressed(none, Key::Delete) || pressed(none, Key::Backspace) {
            if state == CageState::Drawing {
                if let Some(draft) = &mut self.cage.draft {
                    draft.pop();
                }
            } else {
                self.delete_cage_vertices();
            }
        }
        if pressed(none, Key::Escape) {
            self.end_cage_gesture();
            self.cage.draft = None;
            self.cage.selected.clear();
        }
        let count = self.shown_cage().len();
        if count > 0 {
            let focus = self.cage.focus();
            let next = if pressed(Modifiers::SHIFT, Key::N) {
                Some(focus.map_or(count - 1, |s| (s + count - 1) % count))
            } else if pressed(none, Key::N) {
                Some(focus.map_or(0, |s| (s + 1) % count))
            } else {
                None
            };
            if let Some(next) = next {
                self.cage.selected = vec![next];
            }
        }
    }

    /// Ends a cage drag or box selection in progress (the document is about to change
    /// under it).
    pub(crate) fn end_cage_gesture(&mut self) {
        self.finish_cage_gesture();
    }

    /// The support contour of cage vertex `focus`'s coordinate function at `10⁻³/n`,
    /// cached per vertex and weights.
    fn support_contour(&mut self, focus: usize) -> Option<Arc<Vec<ContourSegment>>> {
        let doc = self.doc.as_ref()?;
        let key = (focus, doc.weights_version);
        if let Some((k, segments)) = &self.cage.contour
            && *k == key
        {
            return Some(segments.clone());
        }
        let solution = doc.cage_solution()?;
        let values = doc.cage_influence(focus)?;
        let n = solution.weights.cage_vertices().max(1);
        let level = 1e-3 / n as f32;
        let segments = Arc::new(contour(solution.domain.triangles(), &values, level));
        self.cage.contour = Some((key, segments.clone()));
        Some(segments)
    }

    /// Draws the cage (and the polygon being drawn, a box selection, the support
    /// contour) over the canvas.
    pub(crate) fn paint_cage(&mut self, painter: &egui::Painter, pointer: Option<Pos2>) {
        let state = self.cage_state();
        let v = self.viewport;
        let warps = self.cage_warping();
        if warps && self.show.heat && self.show.contour {
            self.paint_contour(painter);
        }
        let Some(doc) = &self.doc else { return };
        let selected = |i: usize| self.cage.selected.contains(&i);
        match state {
            CageState::Drawing => {
                if doc.method() != Method::Lbc && doc.cage().is_some() && self.cage.draft.is_none()
                {
                    // A cage kept from LBC: faint, for reference.
                    let rest: Vec<Pos2> = doc.cage_rest().iter().map(|p| v.to_screen(*p)).collect();
                    painter.add(Shape::closed_line(rest, Stroke::new(1.0, CAGE_REST)));
                }
                let Some(draft) = &self.cage.draft else {
                    return;
                };
                let points: Vec<Pos2> = draft.iter().map(|p| v.to_screen(*p)).collect();
                painter.add(Shape::line(points.clone(), Stroke::new(3.0, OUTLINE)));
                painter.add(Shape::line(points.clone(), Stroke::new(1.5, CAGE)));
                if let (Some(last), Some(pointer)) = (points.last(), pointer) {
                    painter.line_segment([*last, pointer], Stroke::new(1.0, CAGE));
                }
                for (i, p) in points.iter().enumerate() {
                    let closing = i == 0
                        && points.len() >= 3
                        && pointer.is_some_and(|q| q.distance(*p) < GRAB);
                    let fill = if closing { SELECTED } else { CAGE };
                    let r = if closing { VERTEX + 2.0 } else { VERTEX };
                    painter.rect(
                        Rect::from_center_size(*p, egui::Vec2::splat(2.0 * r)),
                        0.0,
                        fill,
                        Stroke::new(1.0, OUTLINE),
                        StrokeKind::Middle,
                    );
                }
            }
            CageState::Rest | CageState::Posed => {
                if state == CageState::Posed && doc.cage().is_some_and(|c| c.pose.is_some()) {
                    // The rest cage, faint, to see how far the pose has gone.
                    let rest: Vec<Pos2> = doc.cage_rest().iter().map(|p| v.to_screen(*p)).collect();
                    painter.add(Shape::closed_line(rest, Stroke::new(1.0, CAGE_REST)));
                }
                let points = if state == CageState::Posed {
                    doc.cage_pose()
                } else {
                    doc.cage_rest()
                };
                let screen: Vec<Pos2> = points.iter().map(|p| v.to_screen(*p)).collect();
                let n = screen.len();
                painter.add(Shape::closed_line(
                    screen.clone(),
                    Stroke::new(3.0, OUTLINE),
                ));
                let color = if state == CageState::Rest && !warps {
                    Color32::from_rgb(255, 170, 60)
                } else {
                    CAGE
                };
                painter.add(Shape::closed_line(screen.clone(), Stroke::new(1.5, color)));
                if state == CageState::Rest {
                    for (i, j) in crossing_edges(&points) {
                        for e in [i, j] {
                            painter.line_segment(
                                [screen[e], screen[(e + 1) % n]],
                                Stroke::new(2.5, CROSSING),
                            );
                        }
                    }
                }
                let focus = self.cage.focus();
                for (i, p) in screen.iter().enumerate() {
                    let fill = if selected(i) { SELECTED } else { CAGE };
                    painter.rect(
                        Rect::from_center_size(*p, egui::Vec2::splat(2.0 * VERTEX)),
                        0.0,
                        fill,
                        Stroke::new(1.0, OUTLINE),
                        StrokeKind::Middle,
                    );
                    if focus == Some(i) {
                        painter.circle_stroke(*p, VERTEX + 4.0, Stroke::new(1.5, SELECTED));
                    }
                }
            }
        }
        if let Some((a, b, _)) = self.cage.boxing {
            let rect = Rect::from_two_pos(v.to_screen(a), v.to_screen(b));
            painter.rect(
                rect,
                0.0,
                Color32::from_rgba_unmultiplied(120, 230, 255, 30),
                Stroke::new(1.0, CAGE),
                StrokeKind::Middle,
            );
        }
    }

    /// The support contour of the heat map's vertex, where the pose puts it.
    fn paint_contour(&mut self, painter: &egui::Painter) {
        let Some(focus) = self.cage.focus() else {
            return;
        };
        let Some(segments) = self.support_contour(focus) else {
            return;
        };
        let v = self.viewport;
        let Some(deformed) = self.doc.as_mut().and_then(|d| d.cage_deformed()) else {
            return;
        };
        let point = |(a, b, t): EdgePoint| {
            let (pa, pb) = (deformed.get(a as usize), deformed.get(b as usize));
            pa.zip(pb)
                .map(|(pa, pb)| v.to_screen(*pa + (*pb - *pa) * t))
        };
        let shapes: Vec<Shape> = segments
            .iter()
            .filter_map(|&[p, q]| Some([point(p)?, point(q)?]))
            .map(|line| Shape::line_segment(line, Stroke::new(2.0, CONTOUR)))
            .collect();
        painter.extend(shapes);
    }

    /// The coordinates of the cage mesh's vertex under the pointer, beside it.
    pub(crate) fn cage_hover(&mut self, pointer: Pos2) -> Option<String> {
        let at = self.viewport.to_image(pointer);
        if !self.cage_warping() {
            return None;
        }
        let doc = self.doc.as_mut()?;
        let deformed = doc.cage_deformed()?.to_vec();
        let solution = doc.cage_solution()?.clone();
        let positions = solution.domain.positions();
        // The posed triangle under the pointer, then its corner nearest the pointer.
        let vertex = solution.domain.triangles().iter().find_map(|&[a, b, c]| {
            let [pa, pb, pc] = [a, b, c].map(|k| deformed[k as usize]);
            let area = (pb - pa).perp_dot(pc - pa);
            if area.abs() < 1e-12 {
                return None;
            }
            let u = (pb - at).perp_dot(pc - at) / area;
            let w = (pc - at).perp_dot(pa - at) / area;
            if u < -1e-9 || w < -1e-9 || 1.0 - u - w < -1e-9 {
                return None;
            }
            [a, b, c].into_iter().min_by(|&x, &y| {
                deformed[x as usize]
                    .distance(at)
                    .total_cmp(&deformed[y as usize].distance(at))
            })
        })? as usize;
        let mut row = solution.weights.row(vertex).to_vec();
        row.sort_by(|a, b| b.1.total_cmp(&a.1));
        let rest = positions[vertex];
        let mut text = format!(
            "vertex {vertex} at ({:.1}, {:.1}): {} coordinates",
            rest.x,
            rest.y,
            row.len()
        );
        for &(k, w) in row.iter().take(5) {
            text.push_str(&format!("\n{w:>6.3}  cage vertex {}", k + 1));
        }
        if row.len() > 5 {
            text.push_str(&format!("\n… and {} smaller", row.len() - 5));
        }
        Some(text)
    }

    /// The cage section of the side panel: what the tool does now, its buttons, τ and
    /// the density inside the cage.
    pub(crate) fn cage_panel(&mut self, ui: &mut Ui) {
        let Some(doc) = &self.doc else { return };
        let state = self.cage_state();
        let has_cage = doc.cage().is_some();
        let lbc = doc.method() == Method::Lbc;
        let problem = CageKey::of(doc.project()).and_then(|k| k.problem());
        let count = doc.cage().map_or(0, |c| c.rest.len());
        let solution = doc.cage_solution().cloned();
        let text = match state {
            CageState::Drawing => {
                let drawn = self.cage.draft.as_ref().map_or(0, Vec::len);
                format!(
                    "Drawing ({drawn} vertices): click around the subject; click the first \
                     vertex, double-click or press Enter to close. Backspace removes the last."
                )
            }
            CageState::Rest => format!(
                "{count} vertices at rest: drag them to adjust the cage, click an edge to \
                 add one, Alt-click to remove one, then Solve (Enter)."
            ),
            CageState::Posed => format!(
                "{count} vertices, solved: drag a vertex, or select several with a box \
                 (Shift adds) and drag one of them."
            ),
        };
        ui.label(text);
        if let Some(problem) = &problem
            && lbc
        {
            ui.colored_label(ui.visuals().error_fg_color, problem);
        }
        ui.horizontal_wrapped(|ui| match state {
            CageState::Drawing => {
                let closable = self.cage.draft.as_ref().is_some_and(|d| d.len() >= 3);
                if ui
                    .add_enabled(closable, egui::Button::new("Close cage"))
                    .clicked()
                {
                    self.close_cage();
                }
                if self.cage.draft.is_some() && ui.button("Cancel drawing").clicked() {
                    self.cage.draft = None;
                }
                if has_cage && !lbc && ui.button("Use the kept cage").clicked() {
                    let _ = self.edit(Edit::Method(Method::Lbc));
                }
            }
            CageState::Rest | CageState::Posed => {
                if state == CageState::Rest {
                    let solve = egui::Button::new("Solve");
                    if ui
                        .add_enabled(problem.is_none(), solve)
                        .on_hover_text(
                            "Solve the cage's local barycentric coordinates (seconds; \
                             Escape cancels)",
                        )
                        .clicked()
                    {
                        self.solve_cage();
                    }
                }
                if solution.is_some() {
                    let label = if self.cage.edit_rest {
                        "Pose the cage"
                    } else {
                        "Edit the rest cage"
                    };
                    if ui.button(label).clicked() {
                        self.toggle_cage_rest();
                    }
                }
                // Reset pose and Clear cage are among the edit buttons above.
                if ui.button("New cage").clicked() {
                    self.cage.selected.clear();
                    self.cage.draft = Some(Vec::new());
                }
            }
        });
        ui.horizontal_wrapped(|ui| {
            let make = ui.button("Cage from outline").on_hover_text(
                "A cage around everything visible in the picture, a few pixels outside \
                     it, with the number of vertices beside",
            );
            ui.add(
                egui::DragValue::new(&mut self.cage.outline_vertices)
                    .range(3..=200)
                    .prefix("with ")
                    .suffix(" vertices"),
            )
            .on_hover_text("How many vertices a cage from the outline gets");
            if make.clicked() {
                // The button gives up the keys, so Enter goes on to Solve rather than
                // making the cage anew.
                make.surrender_focus();
                self.cage_from_outline();
            }
        });
        if !has_cage {
            return;
        }
        let Some(doc) = &self.doc else { return };
        let current = doc.project().lbc.unwrap_or_default();
        let mut settings = current;
        egui::ComboBox::from_label("Locality weighting τ")
            .selected_text(tau_name(settings.tau))
            .show_ui(ui, |ui| {
                for tau in [Tau::Square, Tau::Linear, Tau::Sqrt, Tau::Constant] {
                    ui.selectable_value(&mut settings.tau, tau, tau_name(tau));
                }
            });
        let current_density = settings
            .density
            .unwrap_or(pipeline::cage::DEFAULT_CAGE_VERTICES);
        // The slider's value while it is dragged; applied when it is released.
        let mut density = self.cage.density_draft.unwrap_or(current_density);
        let r = ui
            .add(
                egui::Slider::new(&mut density, 100..=20_000)
                    .logarithmic(true)
                    .text("Vertices inside"),
            )
            .on_hover_text(
                "The mesh inside the cage the coordinates are solved on: more is smoother \
                 and slower",
            );
        if r.drag_stopped() || (r.changed() && !r.dragged()) {
            settings.density = Some(density);
            self.cage.density_draft = None;
        } else if density != current_density {
            self.cage.density_draft = Some(density);
        }
        if settings != current {
            let _ = self.edit(Edit::Lbc(settings));
        }
        if let Some(solution) = solution {
            let report = &solution.report;
            ui.label(format!(
                "{} mesh vertices inside; {} ADMM iterations{}",
                solution.domain.positions().len(),
                report.iterations,
                if report.converged {
                    ""
                } else {
                    " (not converged)"
                }
            ));
        }
        ui.checkbox(&mut self.show.contour, "Support contour (0.001/n)")
            .on_hover_text(
                "With the heat map: where the selected vertex's coordinate falls below \
                 the paper's threshold of negligible influence",
            );
        ui.checkbox(&mut self.show.locality, "Locality plots");
    }

    /// The panel of the paper's locality statistics of the solved cage (§5, eqs.
    /// 19–21): `P(t)`, the average share of the inside where a coordinate is at most
    /// `t`, and `Q(k)`, the share influenced by at least `k` cage vertices.
    pub(crate) fn locality_panel(&mut self, ui: &mut Ui) {
        ui.heading("Locality");
        // While a new cage is drawn, the old one's statistics would only mislead.
        let drawing = self.cage.draft.is_some();
        let solution = self
            .doc
            .as_ref()
            .filter(|d| d.method() == Method::Lbc && !drawing)
            .and_then(|d| d.cage_solution().cloned());
        let Some(solution) = solution else {
            ui.label(
                "Once the cage is solved, the paper's locality statistics (§5) of its \
                 coordinates show here: P(t), how much of the inside each coordinate leaves \
                 (nearly) untouched, and Q(k), how many cage vertices reach each part of it.",
            );
            return;
        };
        let locality = &solution.locality;
        let n = solution.weights.cage_vertices();
        ui.label(format!(
            "The paper's statistics (§5) of the coordinates of this cage's {n} vertices."
        ));
        let p: Vec<[f64; 2]> = locality
            .t
            .iter()
            .zip(&locality.p)
            .map(|(&t, &p)| [t, p])
            .collect();
        let plot = |id: &str, x: &str, y: &str| {
            egui_plot::Plot::new(id.to_owned())
                .height(170.0)
                .x_axis_label(x.to_owned())
                .y_axis_label(y.to_owned())
                .include_y(0.0)
                .include_y(1.0)
                .allow_zoom(false)
                .allow_drag(false)
                .allow_scroll(false)
                .allow_boxed_zoom(false)
                .allow_double_click_reset(false)
        };
        ui.label("P(t): the share of the inside where a coordinate is at most t, averaged over the cage vertices (eq. 20)");
        let response = plot("locality-p", "t", "P(t)")
            .include_x(0.0)
            .include_x(1.0)
            .show(ui, |plot| {
                plot.line(egui_plot::Line::new("P(t)", p.clone()).color(CAGE));
                plot.points(
                    egui_plot::Points::new("P(t) samples", p.clone())
                        .radius(2.5)
                        .color(CAGE),
                );
            })
            .response;
        response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, "P(t) plot"));
        let q: Vec<[f64; 2]> = locality
            .q
            .iter()
            .enumerate()
            .map(|(k, &q)| [k as f64, q])
            .collect();
        ui.label(
            "Q(k): the share of the inside where at least k coordinates exceed 0.001/n (eq. 21)",
        );
        let response = plot("locality-q", "k", "Q(k)")
            .include_x(0.0)
            .include_x(n as f64)
            // k counts cage vertices: marks at whole numbers.
            .x_grid_spacer(egui_plot::uniform_grid_spacer(|input| {
                let span = (input.bounds.1 - input.bounds.0).max(1.0);
                let unit = 10f64.powf((span / 50.0).log10().ceil().max(0.0));
                [unit, 5.0 * unit, 10.0 * unit]
            }))
            .show(ui, |plot| {
                plot.line(egui_plot::Line::new("Q(k)", q.clone()).color(SELECTED));
                plot.points(
                    egui_plot::Points::new("Q(k) samples", q.clone())
                        .radius(2.5)
                        .color(SELECTED),
                );
            })
            .response;
        response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, "Q(k) plot"));
        // P at the threshold of negligible influence, and the reach in numbers.
        if let Some(&untouched) = locality.p.get(1) {
            ui.label(format!(
                "A coordinate is negligible (at most 0.001/n) on {:.0}% of the inside, on average.",
                untouched * 100.0
            ));
        }
        let most = locality.q.iter().rposition(|&q| q > 0.0).unwrap_or(0);
        let mean: f64 = locality.q.iter().skip(1).sum();
        ui.label(format!(
            "A point is moved by {mean:.1} cage vertices on average, by {most} at most."
        ));
    }

    /// The side panel's edit buttons for the cage, in the method's place of handles.
    pub(crate) fn cage_edit_buttons(&mut self, ui: &mut Ui) {
        if ui.button("Reset pose").clicked() {
            self.reset_cage_pose();
        }
        if ui.button("Clear cage").clicked() {
            self.clear_cage();
        }
    }
}

fn tau_name(tau: Tau) -> &'static str {
    match tau {
        Tau::Square => "x² (the paper's)",
        Tau::Linear => "x",
        Tau::Sqrt => "sqrt(x)",
        Tau::Constant => "1 (plain total variation)",
    }
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
