//! The cage tool's panels: its section of the side panel (what it does now, its
//! buttons, τ and the density inside the cage), its edit buttons, and the panel of the
//! paper's locality statistics of the solved cage.

use egui::Ui;
use pipeline::cage::CageCoordinates;
use project::{Controls, Method, Tau};

use super::{CAGE, CageState, CageTool, SELECTED};
use crate::controls::StatusField;
use crate::document::{CageKey, Document, Edit};
use crate::tool::Host;

/// What the side panel's buttons need to know of the document.
struct Situation {
    state: CageState,
    /// The project has a cage.
    has_cage: bool,
    /// LBC is the method.
    lbc: bool,
    /// Why the cage cannot be solved, if it cannot.
    problem: Option<String>,
    /// The cage is solved.
    solved: bool,
}

impl CageTool {
    /// The cage section of the side panel: what the tool does now, its buttons, τ and
    /// the density inside the cage.
    pub(super) fn cage_panel(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        let Some(doc) = host.document() else { return };
        let state = self.state(Some(doc));
        let count = doc.cage().map_or(0, |c| c.rest.len());
        let solution = doc.cage_solution().cloned();
        let situation = Situation {
            state,
            has_cage: doc.cage().is_some(),
            lbc: doc.method().controls() == Controls::Cage,
            problem: CageKey::of(doc.project()).and_then(|k| k.problem()),
            solved: solution.is_some(),
        };
        ui.label(self.describe(state, count));
        if let Some(problem) = &situation.problem
            && situation.lbc
        {
            ui.colored_label(ui.visuals().error_fg_color, problem);
        }
        ui.horizontal_wrapped(|ui| self.state_buttons(host, ui, &situation));
        ui.horizontal_wrapped(|ui| self.outline_row(host, ui));
        if !situation.has_cage {
            return;
        }
        self.lbc_settings(host, ui);
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
        let show = host.shows_mut();
        ui.checkbox(&mut show.contour, "Support contour (0.001/n)")
            .on_hover_text(
                "With the heat map: where the selected vertex's coordinate falls below \
                 the paper's threshold of negligible influence",
            );
        ui.checkbox(&mut show.locality, "Locality plots");
    }

    /// What the tool does in `state`, with a cage of `count` vertices, in words.
    fn describe(&self, state: CageState, count: usize) -> String {
        match state {
            CageState::Drawing => {
                let drawn = self.draft.as_ref().map_or(0, Vec::len);
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
        }
    }

    /// The buttons of the tool's state: close or cancel the polygon drawn, or solve,
    /// switch between posing and editing at rest, start a new cage.
    fn state_buttons(&mut self, host: &mut dyn Host, ui: &mut Ui, situation: &Situation) {
        let state = situation.state;
        match state {
            CageState::Drawing => {
                let closable = self.draft.as_ref().is_some_and(|d| d.len() >= 3);
                if ui
                    .add_enabled(closable, egui::Button::new("Close cage"))
                    .clicked()
                {
                    self.close(host);
                }
                if self.draft.is_some() && ui.button("Cancel drawing").clicked() {
                    self.draft = None;
                }
                if situation.has_cage && !situation.lbc && ui.button("Use the kept cage").clicked()
                {
                    let _ = self.edit(host, Edit::Method(Method::for_controls(Controls::Cage)));
                }
            }
            CageState::Rest | CageState::Posed => {
                if state == CageState::Rest {
                    let solve = egui::Button::new("Solve");
                    if ui
                        .add_enabled(situation.problem.is_none(), solve)
                        .on_hover_text(
                            "Solve the cage's local barycentric coordinates (seconds; \
                             Escape cancels)",
                        )
                        .clicked()
                    {
                        self.solve(host);
                    }
                }
                if situation.solved {
                    let label = if self.edit_rest {
                        "Pose the cage"
                    } else {
                        "Edit the rest cage"
                    };
                    if ui.button(label).clicked() {
                        self.toggle_rest(host);
                    }
                }
                // Reset pose and Clear cage are among the edit buttons above.
                if ui.button("New cage").clicked() {
                    self.start_new();
                }
            }
        }
    }

    /// "Cage from outline", with the number of vertices it makes.
    fn outline_row(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        let make = ui.button("Cage from outline").on_hover_text(
            "A cage around everything visible in the picture, a few pixels outside \
                 it, with the number of vertices beside",
        );
        ui.add(
            egui::DragValue::new(&mut self.outline_vertices)
                .range(3..=200)
                .prefix("with ")
                .suffix(" vertices"),
        )
        .on_hover_text("How many vertices a cage from the outline gets");
        if make.clicked() {
            // The button gives up the keys, so Enter goes on to Solve rather than
            // making the cage anew.
            make.surrender_focus();
            self.make_from_outline(host);
        }
    }

    /// The project's LBC settings: τ, and the density inside the cage (applied when
    /// its slider is released).
    fn lbc_settings(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        let Some(doc) = host.document() else { return };
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
        let mut density = self.density_draft.unwrap_or(current_density);
        let r = ui
            .add(
                egui::Slider::new(&mut density, 100..=100_000)
                    .logarithmic(true)
                    .text("Vertices inside"),
            )
            .on_hover_text(
                "The mesh inside the cage the coordinates are solved on: more is smoother \
                 and slower (20,000, the picture's own density, by default: a second or \
                 two to solve)",
            );
        if r.drag_stopped() || (r.changed() && !r.dragged()) {
            settings.density = Some(density);
            self.density_draft = None;
        } else if density != current_density {
            self.density_draft = Some(density);
        }
        if settings != current {
            let _ = self.edit(host, Edit::Lbc(settings));
        }
    }

    /// The side panel's edit buttons for the cage, in the method's place of handles.
    pub(crate) fn cage_buttons(&mut self, host: &mut dyn Host, ui: &mut Ui) {
        if ui.button("Reset pose").clicked() {
            self.reset_pose(host);
        }
        if ui.button("Clear cage").clicked() {
            self.clear(host);
        }
    }

    /// The status bar's fields: the cage, and the mesh inside it once solved.
    pub(crate) fn status_fields(&self, doc: &Document) -> Vec<StatusField> {
        let cage = doc.cage().map_or(0, |c| c.rest.len());
        let text = match doc.cage_solution() {
            Some(solution) => format!(
                "cage of {cage} vertices; {} mesh vertices inside",
                solution.domain.positions().len()
            ),
            None => format!("cage of {cage} vertices, not solved"),
        };
        vec![(text, None)]
    }

    /// The panel of the paper's locality statistics of the solved cage (§5, eqs.
    /// 19–21): `P(t)`, the average share of the inside where a coordinate is at most
    /// `t`, and `Q(k)`, the share influenced by at least `k` cage vertices.
    pub(crate) fn locality_panel(&self, host: &dyn Host, ui: &mut Ui) {
        ui.heading("Locality");
        // While a new cage is drawn, the old one's statistics would only mislead.
        let drawing = self.draft.is_some();
        let solution = host
            .document()
            .filter(|d| d.method().controls() == Controls::Cage && !drawing)
            .and_then(|d| d.cage_solution().cloned());
        let Some(solution) = solution else {
            ui.label(
                "Once the cage is solved, the paper's locality statistics (§5) of its \
                 coordinates show here: P(t), how much of the inside each coordinate leaves \
                 (nearly) untouched, and Q(k), how many cage vertices reach each part of it.",
            );
            return;
        };
        locality_plots(ui, &solution);
    }
}

/// The plots of `P(t)` and `Q(k)` of `solution`'s coordinates, and their summary.
fn locality_plots(ui: &mut Ui, solution: &CageCoordinates) {
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
    ui.label("Q(k): the share of the inside where at least k coordinates exceed 0.001/n (eq. 21)");
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

/// A fixed plot (no zoom, drag or scroll) from 0 to 1 high, with its axes named.
fn plot(id: &str, x: &str, y: &str) -> egui_plot::Plot<'static> {
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
}

fn tau_name(tau: Tau) -> &'static str {
    match tau {
        Tau::Square => "x² (the paper's)",
        Tau::Linear => "x",
        Tau::Sqrt => "sqrt(x)",
        Tau::Constant => "1 (plain total variation)",
    }
}
