//! Which overlays the canvas draws.

/// Which overlays are on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Show {
    /// Mesh edges.
    pub mesh: bool,
    /// Virtual handles.
    pub virtual_handles: bool,
    /// Voronoi cells of all nodes.
    pub cells: bool,
    /// The dual (Delaunay) graph of the nodes.
    pub dual_graph: bool,
    /// The selected handle's weight as a heat map with isolines.
    pub heat: bool,
    /// Fold-overs in red.
    pub folds: bool,
    /// The overlap regions automatic depth orders: each front sheet outlined in
    /// yellow, each back sheet in blue.
    pub overlaps: bool,
    /// The weights under the cursor.
    pub hover_weights: bool,
    /// Painted rigidity, translucent.
    pub rigidity: bool,
    /// With the heat map of a cage vertex: its support contour at `10⁻³/n`.
    pub contour: bool,
    /// The panel of a solved cage's locality statistics.
    pub locality: bool,
}

impl Default for Show {
    fn default() -> Self {
        Self {
            mesh: false,
            virtual_handles: true,
            cells: false,
            dual_graph: false,
            heat: false,
            folds: true,
            overlaps: false,
            hover_weights: true,
            rigidity: true,
            contour: true,
            locality: true,
        }
    }
}
