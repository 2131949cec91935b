//! The rig / project file (RIG.json): what a user keeps of a warp.
//!
//! ```json
//! {"version": 1, "alpha": 1.0, "degree": 5, "fixed_boundary": false,
//!  "handles": [
//!    {"type": "point", "rest": [120, 80], "translate": [10, 0], "rotate": 0.3, "scale": 1.0},
//!    {"type": "bar", "rest": [[40, 200], [160, 200]], "pose": [[40, 210], [160, 190]]}
//!  ]}
//! ```
//!
//! Coordinates are image pixels, origin top-left, y down; angles in radians. Every
//! field but `version` and `handles` has a default, so hand-written rigs stay short.
//! The file carries no `NaN` (JSON cannot), and [`Project::validate`] refuses
//! infinities, out-of-range options and handles off the image.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

#[macro_use]
mod names;
pub mod animation;

use std::sync::Arc;

pub use animation::{Animation, HandlePose, Interpolation, Key, Pose, SpatialKey};

/// The largest pose coordinate (pixels) or rotation (radians) a handle may have (the
/// numeric core refuses larger ones too: blending them could overflow).
pub const MAX_POSE: f64 = 1e9;
/// The smallest scale of a point handle.
pub const MIN_SCALE: f64 = 1e-9;
/// The largest scale of a point handle.
pub const MAX_SCALE: f64 = 1e9;

/// The file format version this crate reads and writes.
pub const VERSION: u32 = 1;

/// The most handles a rig file may have: the weights are built for up to this many
/// (`weights_core::MAX_HANDLES`; this crate does not depend on it, and the pipeline's
/// tests check that the two agree). A larger rig is refused with a message naming the
/// limit before anything is computed.
pub const MAX_HANDLES: usize = 10_000;

/// Which distance the weights use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum MetricChoice {
    /// Euclidean for an opaque (rectangular) image, intrinsic for a cut-out.
    #[default]
    Auto,
    /// Straight-line distance everywhere.
    Euclidean,
    /// Shortest paths inside the shape.
    Intrinsic,
}

/// Which published method warps the picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// The closed-form C² weights of Xian, Jin and Wang, with virtual handles.
    #[default]
    C2,
    /// As-rigid-as-possible shape manipulation (Igarashi, Moscovich and Hughes 2005).
    Arap,
    /// Moving least squares image deformation (Schaefer, McPhail and Warren 2006).
    Mls,
    /// Local barycentric coordinates of a cage (Zhang et al. 2014).
    Lbc,
}

impl Method {
    /// Every method, in the order a user is offered them.
    pub const ALL: [Method; 4] = [Method::C2, Method::Arap, Method::Mls, Method::Lbc];

    /// The name in rig files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::C2 => "c2",
            Method::Arap => "arap",
            Method::Mls => "mls",
            Method::Lbc => "lbc",
        }
    }

    /// The name shown to users.
    pub fn label(self) -> &'static str {
        match self {
            Method::C2 => "C² weights",
            Method::Arap => "ARAP",
            Method::Mls => "MLS",
            Method::Lbc => "LBC cage",
        }
    }

    /// What it does, in a sentence for users (the method selector's tooltip).
    pub fn about(self) -> &'static str {
        match self {
            Method::C2 => {
                "closed-form C² weights (Xian, Jin and Wang): smooth and local, with virtual \
                 handles; the handles' rotation and scale blend too"
            }
            Method::Arap => {
                "as-rigid-as-possible (Igarashi, Moscovich and Hughes 2005): shapes keep \
                 their proportions; each pin holds a small disc around it"
            }
            Method::Mls => {
                "moving least squares (Schaefer, McPhail and Warren 2006): at each point, \
                 the map (rigid by default) that best fits the handles near it; distances \
                 are straight lines, so a handle also pulls what lies near it across a gap"
            }
            Method::Lbc => {
                "local barycentric coordinates (Zhang et al. 2014): a cage drawn around \
                 the subject moves what lies inside it, each vertex only its \
                 neighbourhood; the outside stays"
            }
        }
    }

    /// What the artist moves to drive it.
    pub fn controls(self) -> Controls {
        match self {
            Method::C2 | Method::Arap | Method::Mls => Controls::Handles,
            Method::Lbc => Controls::Cage,
        }
    }

    /// The method a rig switches to when it gets `controls` of that kind and has none
    /// chosen for them: C² for handles, LBC for a cage.
    pub fn for_controls(controls: Controls) -> Method {
        match controls {
            Controls::Handles => Method::C2,
            Controls::Cage => Method::Lbc,
        }
    }

    /// Whether the method reads the painted rigidity (`"rigidity"`): ARAP.
    pub fn reads_rigidity(self) -> bool {
        matches!(self, Method::Arap)
    }

    /// Whether choosing the method sets a solver up on the picture's mesh (ARAP
    /// factorises its systems, MLS precomputes its fits), which takes a noticeable time
    /// on a large mesh.
    pub fn sets_up_on_the_mesh(self) -> bool {
        matches!(self, Method::Arap | Method::Mls)
    }

    /// Whether the method weighs the picture by the C² rig's nodes, so the virtual
    /// handles and their dual graph mean something for it: C² itself.
    pub fn uses_virtual_handles(self) -> bool {
        matches!(self, Method::C2)
    }

    /// The names of every method, for messages: `c2, arap, mls, lbc`.
    pub fn names() -> String {
        Method::ALL.map(Method::name).join(", ")
    }
}

/// What the artist moves to drive a method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Controls {
    /// Point and bar handles on the picture (the rig file's `"handles"`).
    Handles,
    /// A cage around the picture (the rig file's `"cage"`).
    Cage,
}

impl std::str::FromStr for Method {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown method {s:?} (known: {})", Method::names()))
    }
}

/// A painted stroke of rigidity (ARAP, the paper's §5.2): every triangle whose
/// centroid lies within `radius` pixels of the polyline `stroke` takes `weight` (the
/// largest where strokes overlap; 1 elsewhere).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidityStroke {
    /// The brush's path in image pixels; one point paints a disc.
    pub stroke: Vec<[f64; 2]>,
    /// The brush radius in pixels.
    pub radius: f64,
    /// The weight of the painted triangles (the paper paints 10000).
    pub weight: f64,
    /// Drawn as parts: the layer (an index into the picture's layers) the stroke
    /// paints — the part under the brush where the stroke began; `None`: every part
    /// it reaches (and the picture, drawn as one, always).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<usize>,
}

/// A cage for local barycentric coordinates: a simple polygon in image pixels (either
/// orientation) and where each of its vertices is posed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CageSpec {
    /// The cage at rest.
    pub rest: Vec<[f64; 2]>,
    /// The posed cage, one point per rest vertex (default: at rest).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose: Option<Vec<[f64; 2]>>,
}

/// The locality weighting `τ` of local barycentric coordinates (the paper's eq. 12).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Tau {
    /// `τ(x) = x²`, the paper's choice.
    #[default]
    Square,
    /// `τ(x) = x`.
    Linear,
    /// `τ ≡ 1`.
    Constant,
    /// `τ(x) = √x`.
    Sqrt,
}

/// Settings of local barycentric coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct LbcSettings {
    /// The locality weighting.
    #[serde(default)]
    pub tau: Tau,
    /// Target number of mesh vertices inside the cage, where the coordinates are
    /// solved (default: the rig's `density`, else the tools' cage default). Kept apart
    /// from `density` so that a project can hold both a picture mesh for handles and a
    /// much smaller mesh for the cage: the solve's time grows quickly with the count.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<usize>,
}

/// ARAP's settings: how far each handle holds and how fine ARAP's own mesh is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ArapSettings {
    /// Radius in pixels of what a handle holds: the mesh vertices within it of a point
    /// handle (within it of the segment, for a bar) move with the handle. 0 pins only
    /// the handle's nearest vertex, as the paper does. Default: 2% of the picture's
    /// diagonal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pin_radius: Option<f64>,
    /// Target vertex count of ARAP's own mesh of the picture, which the picture's mesh
    /// follows (the paper solves on a few hundred vertices; a single vertex of a fine
    /// mesh has too little hold). Default: 3,000.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<usize>,
    /// How a pose is solved: the paper's two steps refined by local/global iterations
    /// to the ARAP energy's minimum (the default on a picture), or the paper's two
    /// steps alone (the default on a mesh given as ARAP's own, `c2warp deform --mesh`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<ArapSolver>,
}

/// How ARAP solves a pose.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ArapSolver {
    /// Igarashi et al.'s two closed-form steps (scale-free fit, then scale adjustment).
    TwoStep,
    /// The two steps, then local/global iterations (Sorkine and Alexa 2007) to the
    /// minimum of the ARAP energy the pins define.
    LocalGlobal,
}

/// Moving least squares' settings: the weight exponent and the class of map fitted at
/// every point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MlsSettings {
    /// The weight exponent α: a handle at distance `r` pixels weighs `1 / r^{2α}` (a
    /// bar: that, integrated along it). Larger is more local. Default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha: Option<f64>,
    /// The class of map fitted: rigid (the default), similarity or affine.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variant: Option<MlsVariant>,
}

/// The largest `mls.alpha`: beyond, weights over a picture's distances leave the
/// range of floating point.
pub const MAX_MLS_ALPHA: f64 = 10.0;

/// The class of map moving least squares fits at every point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum MlsVariant {
    /// Rotation and translation (the paper's §2.3).
    #[default]
    Rigid,
    /// Rotation, uniform scale and translation (§2.2).
    Similarity,
    /// Any affine map (§2.1).
    Affine,
}

impl MlsVariant {
    /// Every variant, in the order a menu lists them.
    pub const ALL: [MlsVariant; 3] = [
        MlsVariant::Rigid,
        MlsVariant::Similarity,
        MlsVariant::Affine,
    ];

    /// The name a menu shows.
    pub fn label(self) -> &'static str {
        match self {
            MlsVariant::Rigid => "Rigid",
            MlsVariant::Similarity => "Similarity",
            MlsVariant::Affine => "Affine",
        }
    }
}

/// The largest `arap.density`: ARAP factorises its mesh when handles change, which
/// takes about a second at this size.
pub const MAX_ARAP_DENSITY: usize = 200_000;

/// The smallest rigidity weight accepted: far below, a painted triangle has no
/// stiffness left and the systems lose precision.
pub const MIN_RIGIDITY: f64 = 1e-3;

/// The most vertices a cage may have.
pub const MAX_CAGE_VERTICES: usize = 1000;

/// The largest rigidity weight accepted (the paper paints 10⁴; far beyond, the
/// systems lose precision).
pub const MAX_RIGIDITY: f64 = 1e8;

/// The most points all rigidity strokes of a rig may have together.
pub const MAX_STROKE_POINTS: usize = 100_000;

/// Placement of the basis's middle Bézier controls (degrees above 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Middle {
    /// All 0.5.
    #[default]
    Half,
    /// On the line between the outer controls.
    Linear,
}

/// How Algorithm 1 places virtual handles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Placement {
    /// The paper's loop: one virtual handle at a time, in the worst cell.
    #[default]
    AsWritten,
    /// Tied worst cells together, close candidates merged: mirror-symmetric rigs get
    /// mirror-symmetric virtual handles.
    Symmetric,
}

deserialize_by_name!(MetricChoice, "a metric", [
    "auto" => MetricChoice::Auto,
    "euclidean" => MetricChoice::Euclidean,
    "intrinsic" => MetricChoice::Intrinsic,
]);
deserialize_by_name!(Method, "a method", [
    "c2" => Method::C2,
    "arap" => Method::Arap,
    "mls" => Method::Mls,
    "lbc" => Method::Lbc,
]);
deserialize_by_name!(MlsVariant, "an MLS variant", [
    "rigid" => MlsVariant::Rigid,
    "similarity" => MlsVariant::Similarity,
    "affine" => MlsVariant::Affine,
]);
deserialize_by_name!(Tau, "a locality weighting τ", [
    "square" => Tau::Square,
    "linear" => Tau::Linear,
    "constant" => Tau::Constant,
    "sqrt" => Tau::Sqrt,
]);
deserialize_by_name!(Middle, "middle controls", [
    "half" => Middle::Half,
    "linear" => Middle::Linear,
]);
deserialize_by_name!(Placement, "a placement", [
    "as_written" => Placement::AsWritten,
    "symmetric" => Placement::Symmetric,
]);

fn is_as_written(placement: &Placement) -> bool {
    *placement == Placement::AsWritten
}

/// The frame an exported or rendered picture has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Canvas {
    /// The picture's own rectangle: what the warp moves beyond its edge is cut off.
    #[default]
    Keep,
    /// The picture's rectangle grown to hold all of the warped picture.
    Fit,
}

deserialize_by_name!(Canvas, "a canvas", [
    "keep" => Canvas::Keep,
    "fit" => Canvas::Fit,
]);

impl std::str::FromStr for Canvas {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "keep" => Ok(Canvas::Keep),
            "fit" => Ok(Canvas::Fit),
            _ => Err(format!("unknown canvas {s:?} (known: keep, fit)")),
        }
    }
}

fn is_keep(canvas: &Canvas) -> bool {
    *canvas == Canvas::Keep
}

/// One handle as stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum HandleSpec {
    /// A point handle.
    Point {
        /// Rest position.
        rest: [f64; 2],
        /// Displacement of the handle.
        #[serde(default)]
        translate: [f64; 2],
        /// Rotation about the rest position, radians.
        #[serde(default)]
        rotate: f64,
        /// Uniform scale about the rest position.
        #[serde(default = "one")]
        scale: f64,
        /// Overlap order: where warped parts overlap, the part nearest a handle of
        /// greater depth is drawn in front.
        #[serde(default, skip_serializing_if = "is_zero")]
        depth: i32,
    },
    /// A bar (segment) handle.
    Bar {
        /// Rest end points.
        rest: [[f64; 2]; 2],
        /// Posed end points (default: at rest).
        #[serde(default)]
        pose: Option<[[f64; 2]; 2]>,
        /// Overlap order, as for a point handle.
        #[serde(default, skip_serializing_if = "is_zero")]
        depth: i32,
    },
}

impl HandleSpec {
    /// Whether the handle is away from its rest pose.
    pub fn is_posed(&self) -> bool {
        match *self {
            Self::Point {
                translate,
                rotate,
                scale,
                ..
            } => translate != [0.0; 2] || rotate != 0.0 || scale != 1.0,
            Self::Bar { rest, pose, .. } => pose.is_some_and(|p| p != rest),
        }
    }
}

impl HandleSpec {
    /// The handle's overlap depth.
    pub fn depth(&self) -> i32 {
        match *self {
            HandleSpec::Point { depth, .. } | HandleSpec::Bar { depth, .. } => depth,
        }
    }

    /// The same handle with its pose reset (at rest, its depth kept).
    pub fn at_rest(&self) -> Self {
        match *self {
            Self::Point { rest, depth, .. } => Self::Point {
                rest,
                translate: [0.0; 2],
                rotate: 0.0,
                scale: 1.0,
                depth,
            },
            Self::Bar { rest, depth, .. } => Self::Bar {
                rest,
                pose: None,
                depth,
            },
        }
    }

    /// The same handle with depth `depth`.
    pub fn with_depth(&self, depth: i32) -> Self {
        let mut h = self.clone();
        match &mut h {
            HandleSpec::Point { depth: d, .. } | HandleSpec::Bar { depth: d, .. } => *d = depth,
        }
        h
    }
}

fn is_zero(x: &i32) -> bool {
    *x == 0
}

fn one() -> f64 {
    1.0
}
fn default_alpha() -> f64 {
    1.0
}
fn default_degree() -> u32 {
    5
}

/// The project: which image, how it is meshed and weighted, and the handles.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Project {
    /// Format version; must be [`VERSION`].
    pub version: u32,
    /// The image, relative to the project file (optional for a bare rig): a picture,
    /// or layered artwork (PSD, OpenRaster).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<PathBuf>,
    /// Several pictures drawn as the layers of one (bottom first, each at the origin),
    /// relative to the project file; instead of `image`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub images: Vec<PathBuf>,
    /// Shape factor α ∈ [0, 1].
    #[serde(default = "default_alpha")]
    pub alpha: f64,
    /// Basis degree n ≥ 5.
    #[serde(default = "default_degree")]
    pub degree: u32,
    /// Middle controls of the basis.
    #[serde(default)]
    pub middle: Middle,
    /// Pin the image border.
    #[serde(default)]
    pub fixed_boundary: bool,
    /// Distance choice.
    #[serde(default)]
    pub metric: MetricChoice,
    /// How virtual handles are placed (omitted for the paper's rule).
    #[serde(default, skip_serializing_if = "is_as_written")]
    pub placement: Placement,
    /// Target number of mesh vertices (default: the tool's default density).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<usize>,
    /// The handles, in order.
    pub handles: Vec<HandleSpec>,
    /// Virtual handles placed so far (rest positions), so a saved rig reloads with
    /// exactly the weights it had. Omit to let them be computed afresh.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub virtual_handles: Vec<[f64; 2]>,
    /// For each of [`Project::virtual_handles`], in the same order, the index into
    /// [`Project::handles`] of the handle it was placed for (`null` for none), so that
    /// removing that handle after a reload takes it along, as it would have before.
    /// Either empty (omitted: no virtual handle was placed for a handle, as in files
    /// from before this field) or as long as `virtual_handles`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub virtual_placed_for: Vec<Option<usize>>,
    /// For each of [`Project::virtual_handles`], in the same order, which of the mesh's
    /// vertices at its place it sits on: 0 the first in the mesh's order, 1 the next. A
    /// cut doubles the vertices along it, one for each side, and a virtual handle on
    /// one side weighs otherwise than on the other. Either empty (omitted: every one on
    /// the first) or as long as `virtual_handles`; a copy the mesh does not have at
    /// that place (a file saved from another mesh) means the first.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub virtual_copy: Vec<usize>,
    /// The warping method (`"c2"` when absent, so older files load unchanged).
    #[serde(default, skip_serializing_if = "is_c2")]
    pub method: Method,
    /// Painted rigidity (used by ARAP; kept with the file whatever the method).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub rigidity: Vec<RigidityStroke>,
    /// The cage (used by LBC).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cage: Option<CageSpec>,
    /// LBC's settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lbc: Option<LbcSettings>,
    /// ARAP's settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub arap: Option<ArapSettings>,
    /// Moving least squares' settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mls: Option<MlsSettings>,
    /// The frame of an export or render: the picture's own (`"keep"`, the default) or
    /// grown to fit the warped picture (`"fit"`).
    #[serde(default, skip_serializing_if = "is_keep")]
    pub canvas: Canvas,
    /// Key poses in time and on the canvas.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub animation: Option<Animation>,
    /// What handles placed in a posed state hold (ARAP): the picture under each as it
    /// was when it was placed, so that placing it moved nothing. See [`Hold`].
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub holds: Vec<Hold>,
    /// The shapes the picture or its parts carry (see [`CarriedShape`]), one each at
    /// most.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub carried: Vec<Arc<CarriedShape>>,
    /// Handles placed in a posed state (indices into `handles`, ascending), which the
    /// C² weights lay over the weights they were placed on instead of re-partitioning
    /// the shape, so that placing one moves nothing away from it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub overlaid: Vec<usize>,
    /// Strokes that separate the shape along them (`"cuts": [{"stroke": [[x, y], …]}]`),
    /// so that parts of a flat picture that touch move apart: the mesh is split along
    /// each stroke's parts inside the shape, so no distance crosses it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cuts: Vec<Cut>,
    /// Automatic depth adjustment (the ARAP paper's §5.1): where the warped picture
    /// overlaps itself, each overlap region is drawn wholly in front or wholly behind,
    /// and keeps its order while it lasts. On unless `false`.
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub auto_depth: bool,
    /// The order of the overlap regions in the pose the handles hold (what automatic
    /// depth decided, so that a reopened file draws what was shown).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub overlaps: Vec<OverlapOrder>,
    /// A layered picture drawn as parts (each layer meshed and moved on its own): the
    /// parts' draw order, visibility and bindings. Absent: the picture is drawn as one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parts: Option<PartsSpec>,
}

/// How a layered picture is drawn as parts (`"parts"`). Parts are named by their
/// layer's index in the file, bottom first.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartsSpec {
    /// The draw order, bottom first: every layer's index once. Empty: the file's order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub order: Vec<usize>,
    /// The layers shown as hidden here whatever the file says (the file's hidden
    /// layers stay hidden unless listed in `shown`), ascending.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hidden: Vec<usize>,
    /// The layers the file hides that are shown here, ascending.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shown: Vec<usize>,
    /// Handles bound to the parts named rather than to every visible part under them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bindings: Vec<Binding>,
    /// The layers locked against new handles and rigidity paint, ascending: a handle
    /// placed over a locked part binds the unlocked parts under it alone (written to
    /// `bindings`). What already binds a locked part keeps moving it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub locked: Vec<usize>,
}

/// A shape the picture (or a part of it) carries, kept so that an edit in a posed
/// state moves nothing: an offset of each of its mesh's vertices from where its
/// method puts it, in the method's local frame there (the closest similarity to the
/// warp around the vertex, its rotation and scale undone), so that it turns and
/// scales with the picture as the handles move it. The vertices are listed by their
/// rest positions (the mesh it was made on, which a file meshes again alike); on
/// another mesh, a vertex between them takes the offset interpolated linearly over
/// their Delaunay triangles, and one off them its nearest listed vertex's. Offsets are
/// kept to 10⁻⁷ px.
///
/// On one picture, under ARAP and MLS, a handle removed in a pose leaves the picture
/// away from it where it was, and under MLS a handle placed in a pose moves nothing.
/// Drawn as parts (under every method), a part that followed another keeps the shape
/// following gave it when a pin first binds it in a pose, a part a removed pin bound
/// stays where it was away from it, and under MLS a part a new pin binds moves
/// nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CarriedShape {
    /// Drawn as parts: the part (its layer's index); `None`: the picture as one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<usize>,
    /// The vertices' rest positions, image pixels.
    pub rest: Vec<[f64; 2]>,
    /// Each vertex's offset, in pixels of the local frame.
    pub offset: Vec<[f64; 2]>,
}

/// The most vertices a [`CarriedShape`] may list.
pub const MAX_CARRIED_POINTS: usize = 1_000_000;

/// A handle bound to chosen parts only (`{"handle": 3, "parts": [2]}`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Binding {
    /// The handle (an index into [`Project::handles`]).
    pub handle: usize,
    /// The parts it binds (layer indices), ascending, at least one.
    pub parts: Vec<usize>,
}

/// The most layers a layered picture may have, and so the highest part index + 1.
pub const MAX_PARTS: usize = 1_000;

impl PartsSpec {
    /// Whether layer `layer` is shown, given whether the file shows it.
    pub fn shows(&self, layer: usize, in_file: bool) -> bool {
        if in_file {
            self.hidden.binary_search(&layer).is_err()
        } else {
            self.shown.binary_search(&layer).is_ok()
        }
    }

    /// The draw order of `layers` layers, bottom first (the file's when none is kept).
    pub fn order_of(&self, layers: usize) -> Vec<usize> {
        if self.order.is_empty() {
            (0..layers).collect()
        } else {
            self.order.clone()
        }
    }

    /// Whether layer `layer` is locked against new handles and rigidity paint.
    pub fn is_locked(&self, layer: usize) -> bool {
        self.locked.binary_search(&layer).is_ok()
    }

    /// The parts handle `handle` is bound to, where it is bound to chosen ones.
    pub fn binding(&self, handle: usize) -> Option<&[usize]> {
        self.bindings
            .iter()
            .find(|b| b.handle == handle)
            .map(|b| b.parts.as_slice())
    }

    /// Checks the indices against a picture of `layers` layers.
    ///
    /// # Errors
    /// An order that is not every layer once, or an index past the layers.
    pub fn check_layers(&self, layers: usize) -> Result<(), ProjectError> {
        let bad = |m: String| Err(ProjectError::Invalid(m));
        if !self.order.is_empty() && self.order.len() != layers {
            return bad(format!(
                "parts.order lists {} layers; the picture has {layers}",
                self.order.len()
            ));
        }
        let past = |list: &[usize]| list.iter().copied().find(|&k| k >= layers);
        for (name, list) in [
            ("order", &self.order),
            ("hidden", &self.hidden),
            ("shown", &self.shown),
            ("locked", &self.locked),
        ] {
            if let Some(k) = past(list) {
                return bad(format!(
                    "parts.{name} names layer {k}; the picture has {layers} (0 to {})",
                    layers.saturating_sub(1)
                ));
            }
        }
        for b in &self.bindings {
            if let Some(k) = past(&b.parts) {
                return bad(format!(
                    "parts.bindings binds handle {} to layer {k}; the picture has {layers}",
                    b.handle
                ));
            }
        }
        Ok(())
    }

    /// Checks what needs no picture: `order` a permutation, the lists ascending and
    /// in range, each binding naming a handle of `handles` once, with parts.
    fn validate(&self, handles: usize) -> Result<(), ProjectError> {
        let bad = |m: String| Err(ProjectError::Invalid(m));
        if self.order.len() > MAX_PARTS {
            return bad(format!(
                "parts.order lists {} layers; at most {MAX_PARTS}",
                self.order.len()
            ));
        }
        let mut seen = vec![false; self.order.len()];
        for &k in &self.order {
            if k >= self.order.len() || std::mem::replace(&mut seen[k], true) {
                return bad(format!(
                    "parts.order must list each layer index from 0 to {} once",
                    self.order.len().saturating_sub(1)
                ));
            }
        }
        let ascending = |list: &[usize]| {
            list.len() <= MAX_PARTS
                && list.windows(2).all(|w| w[0] < w[1])
                && list.iter().all(|&k| k < MAX_PARTS)
        };
        for (name, list) in [
            ("hidden", &self.hidden),
            ("shown", &self.shown),
            ("locked", &self.locked),
        ] {
            if !ascending(list) {
                return bad(format!(
                    "parts.{name} must be layer indices below {MAX_PARTS}, ascending, each once"
                ));
            }
        }
        if let Some(k) = self.hidden.iter().find(|k| self.shown.contains(k)) {
            return bad(format!("parts: layer {k} is both hidden and shown"));
        }
        if self.bindings.len() > MAX_HANDLES {
            return bad(format!(
                "parts.bindings has {} entries; at most one a handle",
                self.bindings.len()
            ));
        }
        for (i, b) in self.bindings.iter().enumerate() {
            if b.handle >= handles {
                return bad(format!(
                    "parts.bindings[{i}] names handle {}; there are {handles}",
                    b.handle
                ));
            }
            if self.bindings[..i].iter().any(|o| o.handle == b.handle) {
                return bad(format!(
                    "parts.bindings[{i}]: handle {} is bound twice",
                    b.handle
                ));
            }
            if b.parts.is_empty() || !ascending(&b.parts) {
                return bad(format!(
                    "parts.bindings[{i}].parts must be at least one layer index below \
                     {MAX_PARTS}, ascending, each once"
                ));
            }
        }
        Ok(())
    }
}

impl CarriedShape {
    /// Checks the lists: the same length for `rest` and `offset`, finite coordinates
    /// within bounds.
    fn validate(&self) -> Result<(), String> {
        let n = self.rest.len();
        if self.part.is_some_and(|k| k >= MAX_PARTS) {
            return Err(format!("part must be a layer's index, below {MAX_PARTS}"));
        }
        if self.offset.len() != n || n > MAX_CARRIED_POINTS {
            return Err(format!(
                "rest and offset must list the same vertices (at most {MAX_CARRIED_POINTS}), \
                 got {n} and {}",
                self.offset.len()
            ));
        }
        if (self.rest.iter().chain(&self.offset).flatten())
            .any(|x| !x.is_finite() || x.abs() > MAX_POSE)
        {
            return Err(format!(
                "coordinates must be finite numbers within ±{MAX_POSE:e} pixels"
            ));
        }
        Ok(())
    }
}

/// `value` as indented JSON (two spaces a level), with each list of numbers, and each
/// list of such lists, on one line (`[320.0, 200.0]`): a point reads as one, and the
/// long lists of points (a carried shape's) take a line each rather than a line a
/// number.
fn write_json(value: &serde_json::Value, depth: usize, out: &mut String) {
    use serde_json::Value;
    let numbers = |v: &Value| v.as_array().is_some_and(|a| a.iter().all(Value::is_number));
    let indent = |depth: usize, out: &mut String| out.extend(std::iter::repeat_n("  ", depth));
    match value {
        Value::Array(items) if items.is_empty() => out.push_str("[]"),
        Value::Array(items) if items.iter().all(|v| v.is_number() || numbers(v)) => {
            out.push('[');
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                match item {
                    Value::Array(inner) => {
                        out.push('[');
                        for (j, x) in inner.iter().enumerate() {
                            if j > 0 {
                                out.push_str(", ");
                            }
                            out.push_str(&x.to_string());
                        }
                        out.push(']');
                    }
                    x => out.push_str(&x.to_string()),
                }
            }
            out.push(']');
        }
        Value::Array(items) => {
            out.push_str("[\n");
            for (i, item) in items.iter().enumerate() {
                indent(depth + 1, out);
                write_json(item, depth + 1, out);
                out.push_str(if i + 1 < items.len() { ",\n" } else { "\n" });
            }
            indent(depth, out);
            out.push(']');
        }
        Value::Object(fields) if fields.is_empty() => out.push_str("{}"),
        Value::Object(fields) => {
            out.push_str("{\n");
            for (i, (key, item)) in fields.iter().enumerate() {
                indent(depth + 1, out);
                out.push_str(&Value::String(key.clone()).to_string());
                out.push_str(": ");
                write_json(item, depth + 1, out);
                out.push_str(if i + 1 < fields.len() { ",\n" } else { "\n" });
            }
            indent(depth, out);
            out.push('}');
        }
        scalar => out.push_str(&scalar.to_string()),
    }
}

fn yes() -> bool {
    true
}

fn is_true(value: &bool) -> bool {
    *value
}

/// One overlap region's order: a point of its front sheet and one of its back sheet,
/// at rest (`{"front": {"at": [x, y]}, "back": {"at": [x, y]}}`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OverlapOrder {
    /// A place in the sheet drawn in front.
    pub front: Place,
    /// A place in the sheet drawn behind.
    pub back: Place,
}

/// A place on the picture at rest: a point, and for a layered picture drawn as parts,
/// the part (its layer's index, bottom first) it lies on.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Place {
    /// The point at rest, in pixels.
    pub at: [f64; 2],
    /// The part, for a layered picture drawn as parts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<usize>,
}

/// The most overlap regions a rig file may order.
pub const MAX_OVERLAPS: usize = 10_000;

/// The most points one cut's stroke may have.
pub const MAX_CUT_POINTS: usize = 10_000;

/// The most cuts a rig file may hold.
pub const MAX_CUTS: usize = 1_000;

/// A cut: a stroke (image pixels) along which the shape is separated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cut {
    /// The stroke's points, in order (at least two, not all at one place).
    pub stroke: Vec<[f64; 2]>,
}

/// What a handle placed in a posed state holds (ARAP): the points of ARAP's mesh it
/// pins, with where the picture had them when it was placed — in the handle's own
/// frame (its pose then undone), for step one's result and for the final one. While
/// the handle is posed, each point is pinned to where the handle's pose takes its
/// held place rather than its rest position; at the pose it was placed in, that is
/// exactly where the picture was, so the solve's answer does not change.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hold {
    /// The handle (an index into [`Project::handles`]).
    pub handle: usize,
    /// The points' rest positions (ARAP's mesh vertices), image pixels.
    pub rest: Vec<[f64; 2]>,
    /// Where each was when the handle was placed, in the handle's frame.
    pub at: Vec<[f64; 2]>,
    /// The same for step one's result of the two-step solve (the scale-free fit).
    pub step_one: Vec<[f64; 2]>,
    /// Drawn as parts: the layer (an index into the picture's layers) whose ARAP mesh
    /// the points are on; a handle that binds several parts holds on each. `None`:
    /// the picture's own mesh, as one picture.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<usize>,
}

impl Hold {
    /// Whether this hold is on `part`'s mesh (`None`: the picture drawn as one).
    pub fn is_on(&self, part: Option<usize>) -> bool {
        self.part == part
    }
}

/// The most points a [`Hold`] may list.
pub const MAX_HOLD_POINTS: usize = 100_000;

fn is_c2(method: &Method) -> bool {
    *method == Method::C2
}

impl Default for Project {
    fn default() -> Self {
        Self {
            version: VERSION,
            image: None,
            alpha: 1.0,
            degree: 5,
            middle: Middle::Half,
            fixed_boundary: false,
            metric: MetricChoice::Auto,
            placement: Placement::AsWritten,
            density: None,
            handles: Vec::new(),
            virtual_handles: Vec::new(),
            virtual_placed_for: Vec::new(),
            virtual_copy: Vec::new(),
            method: Method::C2,
            rigidity: Vec::new(),
            cage: None,
            lbc: None,
            arap: None,
            mls: None,
            canvas: Canvas::Keep,
            animation: None,
            holds: Vec::new(),
            carried: Vec::new(),
            overlaid: Vec::new(),
            cuts: Vec::new(),
            auto_depth: true,
            overlaps: Vec::new(),
            parts: None,
            images: Vec::new(),
        }
    }
}

/// The mesh densities (target vertex counts) a rig file or a command may ask for.
pub const DENSITY_RANGE: std::ops::RangeInclusive<usize> = 16..=4_000_000;

/// Checks a mesh density (a target vertex count) against [`DENSITY_RANGE`]: the one
/// rule for a rig file's `density` and a command line's `--density`.
///
/// # Errors
/// [`ProjectError::Density`] outside the range.
///
/// # Example
/// ```
/// assert!(project::validate_density(20_000).is_ok());
/// let err = project::validate_density(0).expect_err("too few");
/// assert_eq!(err.to_string(), "density must be between 16 and 4000000 vertices, got 0");
/// ```
pub fn validate_density(density: usize) -> Result<(), ProjectError> {
    if DENSITY_RANGE.contains(&density) {
        Ok(())
    } else {
        Err(ProjectError::Density(density))
    }
}

/// Why a project cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ProjectError {
    /// Not JSON, or not the expected fields.
    #[error("malformed rig file: {0}")]
    Json(#[from] serde_json::Error),
    /// A field of the wrong type or with an unknown value (`path`: where, as
    /// `handles[2].rest`).
    #[error("malformed rig file: {}{source}", field_prefix(path))]
    Field {
        /// Where in the file.
        path: String,
        /// What is wrong there.
        source: serde_json::Error,
    },
    /// A version this build does not read.
    #[error("unsupported rig file version {0} (this build reads version {VERSION})")]
    Version(u64),
    /// A value out of range.
    #[error("invalid rig: {0}")]
    Invalid(String),
    /// A mesh density outside [`DENSITY_RANGE`].
    #[error(
        "density must be between {min} and {max} vertices, got {0}",
        min = DENSITY_RANGE.start(),
        max = DENSITY_RANGE.end()
    )]
    Density(usize),
}

/// `"path: "` for a field's path, nothing for the whole file.
fn field_prefix(path: &str) -> String {
    if path.is_empty() || path == "." {
        String::new()
    } else {
        format!("{path}: ")
    }
}

impl Project {
    /// Removes handle `index` with what belongs to it: its track in every key and its
    /// hold (the holds of the handles after it are renumbered). Nothing happens for an
    /// index past the end.
    pub fn remove_handle(&mut self, index: usize) {
        if index >= self.handles.len() {
            return;
        }
        self.handles.remove(index);
        if let Some(animation) = &mut self.animation {
            animation.remove_handle(index);
        }
        self.holds.retain(|h| h.handle != index);
        for hold in &mut self.holds {
            if hold.handle > index {
                hold.handle -= 1;
            }
        }
        self.overlaid.retain(|&h| h != index);
        for h in &mut self.overlaid {
            if *h > index {
                *h -= 1;
            }
        }
        if let Some(parts) = &mut self.parts {
            parts.bindings.retain(|b| b.handle != index);
            for b in &mut parts.bindings {
                if b.handle > index {
                    b.handle -= 1;
                }
            }
        }
    }

    /// Whether the picture is posed anywhere: a handle away from rest now or in an
    /// animation key. A handle placed then holds the picture where it is (ARAP's holds,
    /// C²'s overlaid handles).
    pub fn is_posed(&self) -> bool {
        let posed = |h: &HandleSpec| h.is_posed();
        self.handles.iter().any(posed)
            || self.animation.as_ref().is_some_and(|a| {
                a.keys
                    .iter()
                    .map(|k| &k.pose)
                    .chain(a.spatial_keys.iter().map(|k| &k.pose))
                    .any(|p| {
                        p.handles
                            .iter()
                            .zip(&self.handles)
                            .any(|(k, h)| match (k, h) {
                                (
                                    HandlePose::Point {
                                        translate,
                                        rotate,
                                        scale,
                                    },
                                    _,
                                ) => *translate != [0.0; 2] || *rotate != 0.0 || *scale != 1.0,
                                (HandlePose::Bar { pose }, HandleSpec::Bar { rest, .. }) => {
                                    pose != rest
                                }
                                (HandlePose::Bar { .. }, HandleSpec::Point { .. }) => false,
                            })
                    })
            })
    }

    /// Parses and validates (without an image size) a project from JSON text. A
    /// leading UTF-8 byte-order mark is ignored.
    ///
    /// # Errors
    /// Malformed JSON, an unknown version, or values out of range.
    pub fn from_json(text: &str) -> Result<Self, ProjectError> {
        // Editors on Windows like to start UTF-8 with a byte-order mark; JSON has no
        // use for it.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // Read the version first so a future file gets a clear message.
        let value: serde_json::Value = serde_json::from_str(text)?;
        let Some(object) = value.as_object() else {
            let kind = match value {
                serde_json::Value::Null => "null",
                serde_json::Value::Bool(_) => "true or false",
                serde_json::Value::Number(_) => "a number",
                serde_json::Value::String(_) => "a string",
                serde_json::Value::Array(_) => "a list",
                serde_json::Value::Object(_) => "an object",
            };
            return Err(ProjectError::Invalid(format!(
                "a rig file is one JSON object ({{\"version\": {VERSION}, \"handles\": [\u{2026}], \
                 \u{2026}}}), not {kind}"
            )));
        };
        match object.get("version") {
            None => return Err(ProjectError::Invalid("missing \"version\"".into())),
            Some(v) => match v.as_u64() {
                Some(v) if v == u64::from(VERSION) => {}
                Some(v) => return Err(ProjectError::Version(v)),
                None => {
                    return Err(ProjectError::Invalid(format!(
                        "\"version\" must be a whole number ({VERSION}), not {v}"
                    )));
                }
            },
        }
        // Deserialised from the text (not the value) so that errors keep their line
        // and column, and with the path of the field at fault.
        let mut deserializer = serde_json::Deserializer::from_str(text);
        let project: Self = serde_path_to_error::deserialize(&mut deserializer).map_err(|e| {
            let path = e.path().to_string();
            ProjectError::Field {
                path,
                source: e.into_inner(),
            }
        })?;
        project.validate(None)?;
        Ok(project)
    }

    /// The project as pretty-printed JSON (numbers round-trip exactly).
    pub fn to_json(&self) -> String {
        let mut s = String::new();
        if let Ok(value) = serde_json::to_value(self) {
            write_json(&value, 0, &mut s);
        }
        s.push('\n');
        s
    }

    /// Checks ranges and finiteness, the number of handles (at most [`MAX_HANDLES`]),
    /// that [`Project::virtual_placed_for`] matches the virtual handles and names
    /// handles that exist, and with `image_size = Some((w, h))` that every handle lies
    /// on the image.
    ///
    /// # Errors
    /// The first problem found, naming the handle.
    pub fn validate(&self, image_size: Option<(u32, u32)>) -> Result<(), ProjectError> {
        let bad = |m: String| Err(ProjectError::Invalid(m));
        if self.handles.len() > MAX_HANDLES {
            return bad(format!(
                "{} handles; C2Warp is built for up to {MAX_HANDLES} handles",
                self.handles.len()
            ));
        }
        if !self.virtual_placed_for.is_empty() {
            if self.virtual_placed_for.len() != self.virtual_handles.len() {
                return bad(format!(
                    "virtual_placed_for has {} entries for {} virtual handles (one each, or \
                     leave it out)",
                    self.virtual_placed_for.len(),
                    self.virtual_handles.len()
                ));
            }
            if let Some((i, h)) = self
                .virtual_placed_for
                .iter()
                .enumerate()
                .find_map(|(i, h)| h.filter(|&h| h >= self.handles.len()).map(|h| (i, h)))
            {
                return bad(format!(
                    "virtual handle {i} was placed for handle {h}, but there are {} handles",
                    self.handles.len()
                ));
            }
        }
        if !self.virtual_copy.is_empty() && self.virtual_copy.len() != self.virtual_handles.len() {
            return bad(format!(
                "virtual_copy has {} entries for {} virtual handles (one each, or leave it \
                 out)",
                self.virtual_copy.len(),
                self.virtual_handles.len()
            ));
        }
        if let Some(i) = (0..self.overlaid.len()).find(|&i| {
            self.overlaid[i] >= self.handles.len()
                || (i > 0 && self.overlaid[i] <= self.overlaid[i - 1])
        }) {
            return bad(format!(
                "overlaid[{i}] names handle {}: the list must be ascending, each of the {} \
                 handles at most once",
                self.overlaid[i],
                self.handles.len()
            ));
        }
        if self.overlaps.len() > MAX_OVERLAPS {
            return bad(format!(
                "{} overlaps; at most {MAX_OVERLAPS} are accepted",
                self.overlaps.len()
            ));
        }
        for (i, order) in self.overlaps.iter().enumerate() {
            for (side, place) in [("front", &order.front), ("back", &order.back)] {
                if !place.at.iter().all(|c| c.is_finite() && c.abs() <= 1e9) {
                    return bad(format!(
                        "overlaps[{i}].{side}.at is not a finite point within ±1e9"
                    ));
                }
            }
        }
        if let Some(parts) = &self.parts {
            parts.validate(self.handles.len())?;
        }
        if self.image.is_some() && !self.images.is_empty() {
            return bad("a rig file names its picture by \"image\" or \"images\", not both".into());
        }
        if self.images.len() > MAX_PARTS {
            return bad(format!(
                "{} images; at most {MAX_PARTS} are drawn as layers",
                self.images.len()
            ));
        }
        if self.cuts.len() > MAX_CUTS {
            return bad(format!(
                "{} cuts; at most {MAX_CUTS} are accepted",
                self.cuts.len()
            ));
        }
        for (i, cut) in self.cuts.iter().enumerate() {
            let n = cut.stroke.len();
            if !(2..=MAX_CUT_POINTS).contains(&n) {
                return bad(format!(
                    "cuts[{i}].stroke has {n} points; a stroke has 2 to {MAX_CUT_POINTS}"
                ));
            }
            if let Some(j) = cut.stroke.iter().position(|p| {
                !p[0].is_finite() || !p[1].is_finite() || p[0].abs() > 1e9 || p[1].abs() > 1e9
            }) {
                return bad(format!(
                    "cuts[{i}].stroke[{j}] is not a finite point within ±1e9"
                ));
            }
            let first = cut.stroke[0];
            if cut
                .stroke
                .iter()
                .all(|p| (p[0] - first[0]).hypot(p[1] - first[1]) < 1e-6)
            {
                return bad(format!(
                    "cuts[{i}].stroke has no length: its points coincide"
                ));
            }
        }
        let mut held = std::collections::BTreeSet::new();
        for (i, hold) in self.holds.iter().enumerate() {
            if hold.handle >= self.handles.len() || !held.insert((hold.handle, hold.part)) {
                return bad(format!(
                    "holds[{i}] names handle {}: there are {} handles, each held once at most \
                     (once on each part)",
                    hold.handle,
                    self.handles.len()
                ));
            }
            if hold.part.is_some_and(|k| k >= MAX_PARTS) {
                return bad(format!(
                    "holds[{i}].part must be a layer's index, below {MAX_PARTS}"
                ));
            }
            let n = hold.rest.len();
            if hold.at.len() != n || hold.step_one.len() != n || n > MAX_HOLD_POINTS {
                return bad(format!(
                    "holds[{i}]: rest, at and step_one must list the same points (at most \
                     {MAX_HOLD_POINTS}), got {}, {} and {}",
                    n,
                    hold.at.len(),
                    hold.step_one.len()
                ));
            }
            let numbers = hold
                .rest
                .iter()
                .chain(&hold.at)
                .chain(&hold.step_one)
                .flatten();
            if numbers
                .clone()
                .any(|x| !x.is_finite() || x.abs() > MAX_POSE)
            {
                return bad(format!(
                    "holds[{i}]: coordinates must be finite numbers within ±{MAX_POSE:e} pixels"
                ));
            }
        }
        for (i, c) in self.carried.iter().enumerate() {
            c.validate()
                .map_err(|m| ProjectError::Invalid(format!("carried[{i}]: {m}")))?;
            if self.carried[..i].iter().any(|o| o.part == c.part) {
                return bad(format!(
                    "carried[{i}]: {} carries two shapes",
                    match c.part {
                        Some(k) => format!("layer {k}"),
                        None => "the picture".to_owned(),
                    }
                ));
            }
        }
        if !(0.0..=1.0).contains(&self.alpha) {
            return bad(format!("alpha must be in [0, 1], got {}", self.alpha));
        }
        if !(5..=25).contains(&self.degree) {
            return bad(format!(
                "degree must be between 5 and 25, got {}",
                self.degree
            ));
        }
        if let Some(d) = self.density {
            validate_density(d)?;
        }
        let inside = |p: [f64; 2]| match image_size {
            Some((w, h)) => {
                p[0] >= 0.0 && p[1] >= 0.0 && p[0] <= f64::from(w) && p[1] <= f64::from(h)
            }
            None => true,
        };
        for (i, h) in self.handles.iter().enumerate() {
            let (points, numbers): (Vec<[f64; 2]>, Vec<f64>) = match h {
                HandleSpec::Point {
                    rest,
                    translate,
                    rotate,
                    scale,
                    ..
                } => {
                    if *scale <= 0.0 {
                        return bad(format!("handle {i}: scale must be positive, got {scale}"));
                    }
                    (
                        vec![*rest],
                        vec![translate[0], translate[1], *rotate, *scale],
                    )
                }
                HandleSpec::Bar { rest, pose, .. } => {
                    if rest[0] == rest[1] {
                        return bad(format!("handle {i}: bar has zero length"));
                    }
                    let pose = pose.unwrap_or(*rest);
                    (rest.to_vec(), pose.iter().flatten().copied().collect())
                }
            };
            if points
                .iter()
                .flatten()
                .chain(&numbers)
                .any(|x| !x.is_finite())
            {
                return bad(format!("handle {i}: coordinates must be finite numbers"));
            }
            if let HandleSpec::Point { scale, .. } = h
                && !(MIN_SCALE..=MAX_SCALE).contains(scale)
            {
                return bad(format!(
                    "handle {i}: scale must be between {MIN_SCALE:e} and {MAX_SCALE:e}, got {scale}"
                ));
            }
            if numbers.iter().any(|x| x.abs() > MAX_POSE) {
                return bad(format!(
                    "handle {i}: a pose beyond ±{MAX_POSE:e} pixels (or radians) is refused"
                ));
            }
            if let Some(p) = points.iter().find(|p| !inside(**p)) {
                return bad(format!(
                    "handle {i}: rest position ({}, {}) lies outside the image",
                    p[0], p[1]
                ));
            }
        }
        if let Some(p) = self
            .virtual_handles
            .iter()
            .find(|p| !p[0].is_finite() || !p[1].is_finite())
        {
            return bad(format!("virtual handle ({}, {}) is not finite", p[0], p[1]));
        }
        if let Some(cage) = &self.cage {
            if !(3..=MAX_CAGE_VERTICES).contains(&cage.rest.len()) {
                return bad(format!(
                    "a cage needs 3 to {MAX_CAGE_VERTICES} vertices, got {}",
                    cage.rest.len()
                ));
            }
            if let Some(pose) = &cage.pose
                && pose.len() != cage.rest.len()
            {
                return bad(format!(
                    "the cage's pose has {} points for {} rest vertices",
                    pose.len(),
                    cage.rest.len()
                ));
            }
            let all = cage.rest.iter().chain(cage.pose.iter().flatten());
            if all
                .clone()
                .flatten()
                .any(|x| !x.is_finite() || x.abs() > MAX_POSE)
            {
                return bad(format!(
                    "cage coordinates must be finite numbers within ±{MAX_POSE:e} pixels"
                ));
            }
            if let Some(p) = cage.rest.iter().find(|p| !inside(**p)) {
                return bad(format!(
                    "cage vertex ({}, {}) lies outside the image",
                    p[0], p[1]
                ));
            }
        } else if self.method == Method::Lbc {
            return bad("method \"lbc\" needs a \"cage\"".into());
        }
        if let Some(d) = self.lbc.and_then(|l| l.density) {
            validate_density(d)?;
        }
        let points: usize = self.rigidity.iter().map(|s| s.stroke.len()).sum();
        if points > MAX_STROKE_POINTS {
            return bad(format!(
                "rigidity strokes have {points} points; at most {MAX_STROKE_POINTS} are read"
            ));
        }
        for (i, s) in self.rigidity.iter().enumerate() {
            if s.stroke.is_empty() {
                return bad(format!("rigidity stroke {i} has no points"));
            }
            if s.stroke.iter().flatten().any(|x| !x.is_finite()) {
                return bad(format!(
                    "rigidity stroke {i}: coordinates must be finite numbers"
                ));
            }
            if !(s.radius.is_finite() && s.radius > 0.0 && s.radius <= MAX_POSE) {
                return bad(format!(
                    "rigidity stroke {i}: radius must be a positive number of pixels, got {}",
                    s.radius
                ));
            }
            if !(s.weight.is_finite() && (MIN_RIGIDITY..=MAX_RIGIDITY).contains(&s.weight)) {
                return bad(format!(
                    "rigidity stroke {i}: weight must be between {MIN_RIGIDITY} and \
                     {MAX_RIGIDITY:e} (1 is unpainted; the paper paints 10000), got {:?}",
                    s.weight
                ));
            }
            if s.part.is_some_and(|k| k >= MAX_PARTS) {
                return bad(format!(
                    "rigidity stroke {i}: part must be a layer's index, below {MAX_PARTS}"
                ));
            }
        }
        if let Some(arap) = &self.arap {
            if let Some(r) = arap.pin_radius
                && !(r.is_finite() && (0.0..=MAX_POSE).contains(&r))
            {
                return bad(format!(
                    "arap.pin_radius must be a number of pixels, 0 or more, got {r}"
                ));
            }
            if let Some(density) = arap.density {
                validate_density(density)?;
                if density > MAX_ARAP_DENSITY {
                    return bad(format!(
                        "arap.density is at most {MAX_ARAP_DENSITY} vertices (ARAP \
                         factorises its mesh), got {density}"
                    ));
                }
            }
        }
        if let Some(alpha) = self.mls.and_then(|m| m.alpha)
            && !(alpha.is_finite() && alpha > 0.0 && alpha <= MAX_MLS_ALPHA)
        {
            return bad(format!(
                "mls.alpha must be a number above 0 and at most {MAX_MLS_ALPHA}, got {alpha}"
            ));
        }
        if let Some(animation) = &self.animation {
            animation.validate(self).map_err(ProjectError::Invalid)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlaid_handles_are_checked_and_follow_their_handles() {
        let text = r#"{"version":1,"handles":[
            {"type":"point","rest":[10,10]},{"type":"point","rest":[30,10],"translate":[2,0]},
            {"type":"point","rest":[50,10]}],"overlaid":[0,2]}"#;
        let mut project = Project::from_json(text).expect("a rig with overlaid handles");
        assert!(project.is_posed());
        assert_eq!(
            Project::from_json(&project.to_json()).expect("round trip"),
            project
        );
        project.remove_handle(0);
        assert_eq!(project.overlaid, [1], "renumbered, the removed one gone");
        for bad in ["[0,0]", "[2,0]", "[3]"] {
            let text = text.replace("[0,2]", bad);
            let error = Project::from_json(&text).expect_err(bad).to_string();
            assert!(error.contains("overlaid"), "{bad}: {error}");
        }
        let at_rest = text.replace(r#","translate":[2,0]"#, "");
        assert!(!Project::from_json(&at_rest).expect("at rest").is_posed());
    }

    #[test]
    fn parts_are_checked_kept_and_follow_their_handles() {
        let text = r#"{"version":1,"image":"cat.ora","handles":[
            {"type":"point","rest":[10,10]},{"type":"point","rest":[30,10]},
            {"type":"point","rest":[50,10]}],
            "parts":{"order":[2,0,1],"hidden":[1],"shown":[3],"locked":[2],
                     "bindings":[{"handle":0,"parts":[0]},{"handle":2,"parts":[1,2]}]}}"#;
        let mut project = Project::from_json(text).expect("a rig with parts");
        assert_eq!(
            Project::from_json(&project.to_json()).expect("round trip"),
            project
        );
        let parts = project.parts.clone().expect("parts");
        assert_eq!(parts.order_of(3), [2, 0, 1]);
        assert_eq!(PartsSpec::default().order_of(3), [0, 1, 2]);
        assert!(!parts.shows(1, true) && parts.shows(0, true));
        assert!(parts.shows(3, false) && !parts.shows(4, false));
        assert_eq!(parts.binding(2), Some(&[1, 2][..]));
        assert!(parts.is_locked(2) && !parts.is_locked(0));
        assert_eq!(parts.binding(1), None);
        // The order is checked against the picture's layers when it is read.
        let error = parts.check_layers(4).expect_err("4 layers").to_string();
        assert!(error.contains("parts.order lists 3 layers"), "{error}");
        let error = PartsSpec {
            shown: vec![3],
            ..PartsSpec::default()
        }
        .check_layers(3)
        .expect_err("no layer 3")
        .to_string();
        assert!(error.contains("parts.shown names layer 3"), "{error}");
        let error = PartsSpec {
            locked: vec![3],
            ..PartsSpec::default()
        }
        .check_layers(3)
        .expect_err("no layer 3")
        .to_string();
        assert!(error.contains("parts.locked names layer 3"), "{error}");
        project.remove_handle(0);
        let parts = project.parts.as_ref().expect("parts");
        assert_eq!(parts.bindings.len(), 1, "the removed handle's binding gone");
        assert_eq!(parts.bindings[0].handle, 1, "renumbered");
        for (bad, says) in [
            (r#""order":[2,0,1]"#, r#""order":[0,0,1]"#),
            (r#""order":[2,0,1]"#, r#""order":[3,0,1]"#),
            (r#""hidden":[1]"#, r#""hidden":[1,1]"#),
            (r#""hidden":[1]"#, r#""hidden":[3]"#),
            (r#""locked":[2]"#, r#""locked":[2,0]"#),
            (r#""locked":[2]"#, r#""locked":[1000]"#),
            (
                r#"{"handle":2,"parts":[1,2]}"#,
                r#"{"handle":3,"parts":[1]}"#,
            ),
            (
                r#"{"handle":2,"parts":[1,2]}"#,
                r#"{"handle":0,"parts":[1]}"#,
            ),
            (
                r#"{"handle":2,"parts":[1,2]}"#,
                r#"{"handle":2,"parts":[]}"#,
            ),
            (
                r#""image":"cat.ora""#,
                r#""image":"cat.ora","images":["a.png"]"#,
            ),
        ] {
            let text = text.replace(bad, says);
            let error = Project::from_json(&text).expect_err(says).to_string();
            assert!(
                error.contains("parts") || error.contains("images"),
                "{says}: {error}"
            );
        }
        let listed = text.replace(r#""image":"cat.ora""#, r#""images":["a.png","b.png"]"#);
        let listed = Project::from_json(&listed).expect("a list of pictures");
        assert_eq!(listed.images.len(), 2);
        assert!(
            !Project::default().to_json().contains("parts"),
            "absent by default"
        );
    }

    #[test]
    fn holds_are_checked_and_follow_their_handles() {
        let text = r#"{"version":1,"handles":[
            {"type":"point","rest":[10,10]},{"type":"point","rest":[30,10]},
            {"type":"point","rest":[50,10]}],
          "holds":[{"handle":1,"rest":[[30,10]],"at":[[31,12]],"step_one":[[31,11]]},
                   {"handle":2,"rest":[[50,10]],"at":[[52,10]],"step_one":[[52,10]]}]}"#;
        let mut project = Project::from_json(text).expect("a rig with holds");
        assert_eq!(
            Project::from_json(&project.to_json()).expect("round trip"),
            project
        );
        project.remove_handle(1);
        assert_eq!(project.holds.len(), 1);
        assert_eq!(project.holds[0].handle, 1, "renumbered with its handle");
        for (bad, says) in [
            (
                text.replace(r#""handle":2"#, r#""handle":7"#),
                "names handle 7",
            ),
            (
                text.replace(r#""handle":2"#, r#""handle":1"#),
                "held once at most",
            ),
            (
                text.replace("[[52,10]],\"step_one", "[],\"step_one"),
                "same points",
            ),
            (text.replace("[[31,12]]", "[[31,1e300]]"), "finite numbers"),
            (
                text.replace(r#""handle":1,"#, r#""handle":1,"part":1000,"#),
                "a layer's index",
            ),
        ] {
            let error = Project::from_json(&bad).expect_err(says).to_string();
            assert!(error.contains(says), "{error}");
        }
        // Drawn as parts, a handle that binds two parts holds on each, once.
        let joint = text.replace(r#""handle":2,"#, r#""handle":1,"part":3,"#);
        let joint = Project::from_json(&joint).expect("held on the picture and on part 3");
        assert_eq!(joint.holds[1].part, Some(3));
        assert!(joint.holds[1].is_on(Some(3)) && joint.holds[0].is_on(None));
        assert_eq!(
            Project::from_json(&joint.to_json()).expect("round trip"),
            joint
        );
        let twice = text
            .replace(r#""handle":2,"#, r#""handle":1,"part":3,"#)
            .replace(
                r#""handle":1,"rest":[[30"#,
                r#""handle":1,"part":3,"rest":[[30"#,
            );
        let error = Project::from_json(&twice).expect_err("twice on part 3");
        assert!(error.to_string().contains("once on each part"), "{error}");
    }

    fn sample() -> Project {
        Project {
            image: Some("cat.png".into()),
            alpha: 0.75,
            degree: 7,
            middle: Middle::Linear,
            fixed_boundary: true,
            metric: MetricChoice::Intrinsic,
            placement: Placement::Symmetric,
            density: Some(5000),
            handles: vec![
                HandleSpec::Point {
                    rest: [10.5, 20.25],
                    translate: [0.1, -3.0 / 7.0],
                    rotate: std::f64::consts::PI / 3.0,
                    scale: 1.1,
                    depth: 0,
                },
                HandleSpec::Bar {
                    rest: [[1.0, 2.0], [30.0, 40.0]],
                    pose: Some([[1.0 / 3.0, 2.0], [31.0, 41.0]]),
                    depth: 0,
                },
            ],
            virtual_handles: vec![[5.0, 6.0], [0.1, 0.2]],
            virtual_placed_for: vec![Some(1), None],
            method: Method::Arap,
            cage: Some(CageSpec {
                rest: vec![[0.0, 0.0], [50.5, 0.0], [25.0, 1.0 / 3.0]],
                pose: Some(vec![[1.0, 0.0], [50.5, 2.0], [25.0, 40.0]]),
            }),
            lbc: Some(LbcSettings {
                tau: Tau::Sqrt,
                density: Some(500),
            }),
            rigidity: vec![
                RigidityStroke {
                    stroke: vec![[3.0, 4.0], [10.25, 1.0 / 3.0]],
                    radius: 6.5,
                    weight: 10000.0,
                    part: None,
                },
                RigidityStroke {
                    stroke: vec![[20.0, 20.0]],
                    radius: 1.0,
                    weight: 0.5,
                    part: None,
                },
            ],
            ..Project::default()
        }
    }

    #[test]
    fn the_method_defaults_to_c2_and_is_left_out_for_it() {
        let p = Project::from_json(r#"{"version":1,"handles":[]}"#).expect("parses");
        assert_eq!(p.method, Method::C2);
        assert!(p.rigidity.is_empty());
        assert!(!p.to_json().contains("method"), "{}", p.to_json());
        let arap =
            Project::from_json(r#"{"version":1,"method":"arap","handles":[]}"#).expect("parses");
        assert_eq!(arap.method, Method::Arap);
        assert!(arap.to_json().contains(r#""method": "arap""#));
        for m in Method::ALL {
            assert_eq!(m.name().parse::<Method>(), Ok(m));
        }
        assert!("lbc2".parse::<Method>().is_err());
    }

    #[test]
    fn mls_settings_round_trip_and_default_to_rigid_with_alpha_one() {
        let p = Project::from_json(
            r#"{"version":1,"method":"mls","handles":[],"mls":{"alpha":1.5,"variant":"affine"}}"#,
        )
        .expect("parses");
        assert_eq!(p.method, Method::Mls);
        let mls = p.mls.expect("settings");
        assert_eq!(mls.alpha, Some(1.5));
        assert_eq!(mls.variant, Some(MlsVariant::Affine));
        assert_eq!(Project::from_json(&p.to_json()).expect("round trip"), p);
        assert_eq!(MlsVariant::default(), MlsVariant::Rigid);
        let bare =
            Project::from_json(r#"{"version":1,"method":"mls","handles":[]}"#).expect("parses");
        assert!(bare.mls.is_none() && !bare.to_json().contains("\"mls\":"));
    }

    #[test]
    fn round_trip_is_exact() {
        let p = sample();
        let back = Project::from_json(&p.to_json()).expect("parses");
        assert_eq!(p, back);
    }

    #[test]
    fn minimal_rig_gets_defaults() {
        let p = Project::from_json(
            r#"{"version":1,"handles":[{"type":"point","rest":[1,2]},{"type":"bar","rest":[[0,0],[5,0]]}]}"#,
        )
        .expect("parses");
        assert_eq!(p.alpha, 1.0);
        assert_eq!(p.degree, 5);
        assert_eq!(
            p.handles[0],
            HandleSpec::Point {
                rest: [1.0, 2.0],
                translate: [0.0, 0.0],
                rotate: 0.0,
                scale: 1.0,
                depth: 0
            }
        );
    }

    #[test]
    fn bad_files_are_refused_with_a_reason() {
        let cases = [
            ("", "malformed"),
            ("{", "malformed"),
            (r#"{"version":2,"handles":[]}"#, "version 2"),
            (r#"{"handles":[]}"#, "version"),
            (
                r#"{"version":1,"handles":[{"type":"point","rest":[NaN,1]}]}"#,
                "malformed",
            ),
            (
                r#"{"version":1,"handles":[{"type":"point","rest":[1e999,1]}]}"#,
                "",
            ),
            (
                r#"{"version":1,"handles":[{"type":"blob","rest":[1,1]}]}"#,
                "malformed",
            ),
            (r#"{"version":1,"alpha":2,"handles":[]}"#, "alpha"),
            (
                r#"{"version":1,"placement":"greedy","handles":[]}"#,
                r#"placement: invalid value: string "greedy", expected a placement: "as_written" or "symmetric""#,
            ),
            ("null", "a rig file is one JSON object"),
            ("[1, 2]", "not a list"),
            (
                r#"{"version":"1","handles":[]}"#,
                "\"version\" must be a whole number",
            ),
            (
                r#"{"version":1,"handles":[],"method":2}"#,
                r#"method: invalid type: integer `2`, expected a method: "c2", "arap", "mls" or "lbc""#,
            ),
            (
                r#"{"version":1,"handles":[{"type":"point","rest":[1,"x"]}]}"#,
                "handles[0]: invalid type: string \"x\", expected f64",
            ),
            (r#"{"version":1,"degree":3,"handles":[]}"#, "degree"),
            (
                r#"{"version":1,"handles":[{"type":"bar","rest":[[1,1],[1,1]]}]}"#,
                "zero length",
            ),
            (
                r#"{"version":1,"handles":[{"type":"point","rest":[1,1],"scale":0}]}"#,
                "scale",
            ),
            (r#"{"version":1,"handels":[]}"#, "malformed"),
            (
                r#"{"version":1,"density":0,"handles":[]}"#,
                "density must be between 16 and 4000000 vertices, got 0",
            ),
            (
                r#"{"version":1,"density":4000001,"handles":[]}"#,
                "density must be between 16 and 4000000 vertices, got 4000001",
            ),
            (
                r#"{"version":1,"handles":[{"type":"point","rest":[1,1],"scale":1e300}]}"#,
                "scale must be between",
            ),
            (
                r#"{"version":1,"handles":[{"type":"point","rest":[1,1],"translate":[2e9,0]}]}"#,
                "pose beyond",
            ),
            (
                r#"{"version":1,"handles":[{"type":"bar","rest":[[1,1],[2,2]],"pose":[[1,1],[1e10,2]]}]}"#,
                "pose beyond",
            ),
            // A byte-order mark anywhere but at the start is not whitespace.
            ("{\u{feff}\"version\":1,\"handles\":[]}", "malformed"),
            (
                r#"{"version":1,"handles":[],"virtual_handles":[[1,1]],"virtual_placed_for":[null,0]}"#,
                "2 entries for 1 virtual handles",
            ),
            (
                r#"{"version":1,"handles":[{"type":"point","rest":[1,1]}],"virtual_handles":[[1,2]],"virtual_placed_for":[1]}"#,
                "placed for handle 1, but there are 1 handles",
            ),
            (
                r#"{"version":1,"method":"c3","handles":[]}"#,
                r#"invalid value: string "c3", expected a method"#,
            ),
            (
                r#"{"version":1,"handles":[],"rigidity":[{"stroke":[[1,NaN]],"radius":2,"weight":3}]}"#,
                "malformed",
            ),
            (
                r#"{"version":1,"handles":[],"rigidity":[{"stroke":[[1,1e999]],"radius":2,"weight":3}]}"#,
                "out of range",
            ),
            (
                r#"{"version":1,"handles":[],"rigidity":[{"stroke":[[1,1]],"radius":-2,"weight":3}]}"#,
                "radius must be a positive",
            ),
            (
                r#"{"version":1,"handles":[],"rigidity":[{"stroke":[[1,1]],"radius":2,"weight":0}]}"#,
                "weight must be between 0.001 and 1e8",
            ),
            (
                r#"{"version":1,"handles":[],"rigidity":[{"stroke":[[1,1]],"radius":2,"weight":1e-20}]}"#,
                "got 1e-20",
            ),
            (
                r#"{"version":1,"handles":[],"arap":{"pin_radius":-1}}"#,
                "arap.pin_radius must be a number of pixels",
            ),
            (
                r#"{"version":1,"handles":[],"arap":{"density":300000}}"#,
                "arap.density is at most 200000",
            ),
            (
                r#"{"version":1,"handles":[],"arap":{"radius":3}}"#,
                "unknown field `radius`",
            ),
            (
                r#"{"version":1,"handles":[],"mls":{"alpha":0}}"#,
                "mls.alpha must be a number above 0 and at most 10, got 0",
            ),
            (
                r#"{"version":1,"handles":[],"mls":{"alpha":11}}"#,
                "mls.alpha must be a number above 0",
            ),
            (
                r#"{"version":1,"handles":[],"mls":{"variant":"shear"}}"#,
                r#"mls.variant: invalid value: string "shear", expected an MLS variant: "rigid", "similarity" or "affine""#,
            ),
            (
                r#"{"version":1,"handles":[],"mls":{"beta":1}}"#,
                "unknown field `beta`",
            ),
            (
                r#"{"version":1,"handles":[],"rigidity":[{"stroke":[],"radius":2,"weight":1}]}"#,
                "no points",
            ),
            (
                r#"{"version":1,"handles":[],"rigidity":[{"stroke":[[1,1]],"radius":2}]}"#,
                "missing field `weight`",
            ),
            (
                r#"{"version":1,"method":"lbc","handles":[]}"#,
                "needs a \"cage\"",
            ),
            (
                r#"{"version":1,"handles":[],"cage":{"rest":[[0,0],[1,0]]}}"#,
                "3 to 1000 vertices, got 2",
            ),
            (
                r#"{"version":1,"handles":[],"cage":{"rest":[[0,0],[1,0],[0,1]],"pose":[[0,0]]}}"#,
                "pose has 1 points for 3",
            ),
            (
                r#"{"version":1,"handles":[],"cage":{"rest":[[0,0],[1,0],[0,1e300]]}}"#,
                "finite numbers within",
            ),
            (
                r#"{"version":1,"handles":[],"lbc":{"tau":"cubic"}}"#,
                r#"lbc.tau: invalid value: string "cubic", expected a locality weighting τ: "square", "linear", "constant" or "sqrt""#,
            ),
            (
                r#"{"version":1,"handles":[],"lbc":{"density":3}}"#,
                "density must be between 16",
            ),
        ];
        for (text, expected) in cases {
            let err = Project::from_json(text).expect_err(text).to_string();
            assert!(err.contains(expected), "{text}: {err}");
        }
    }

    #[test]
    fn a_byte_order_mark_is_ignored() {
        let text = sample().to_json();
        let with_bom = format!("\u{feff}{text}");
        assert_eq!(Project::from_json(&with_bom).expect("parses"), sample());
    }

    #[test]
    fn handles_must_lie_on_the_image() {
        let p = sample();
        assert!(p.validate(Some((100, 100))).is_ok());
        let err = p
            .validate(Some((20, 20)))
            .expect_err("bar end off the image");
        assert!(err.to_string().contains("outside the image"), "{err}");
    }

    #[test]
    fn files_without_virtual_placed_for_still_load_and_files_with_it_round_trip() {
        let old = r#"{"version":1,"handles":[{"type":"point","rest":[1,2]}],"virtual_handles":[[3,4],[5,6]]}"#;
        let p = Project::from_json(old).expect("an older file");
        assert!(p.virtual_placed_for.is_empty());
        assert!(!p.to_json().contains("virtual_placed_for"));
        let with = Project {
            virtual_placed_for: vec![None, Some(0)],
            ..p
        };
        let text = with.to_json();
        assert!(text.contains("\"virtual_placed_for\""), "{text}");
        assert!(!text.contains("virtual_copy"), "{text}");
        assert_eq!(Project::from_json(&text).expect("parses"), with);
        // Which copy of a vertex doubled by a cut: round-trips, one entry each.
        let copies = Project {
            virtual_copy: vec![0, 1],
            ..with
        };
        let text = copies.to_json();
        assert_eq!(Project::from_json(&text).expect("parses"), copies);
        let short = text.replace("\"virtual_copy\": [0, 1]", "\"virtual_copy\": [1]");
        assert_ne!(short, text);
        let err = Project::from_json(&short).expect_err("one entry for two");
        assert!(
            err.to_string().contains("virtual_copy has 1 entries"),
            "{err}"
        );
    }

    #[test]
    fn a_rig_file_writes_each_point_on_one_line_and_reads_back_the_same() {
        let text = r#"{"version":1,"handles":[{"type":"point","rest":[1,2.5],"translate":[3,4]},
          {"type":"bar","rest":[[1,2],[30,40]]}],
          "carried":[{"rest":[[1,2],[3,4]],"offset":[[0.1234567,-2],[0,0]]},
                     {"part":2,"rest":[[5,6]],"offset":[[1,1]]}]}"#;
        let project = Project::from_json(text).expect("a rig file");
        let written = project.to_json();
        assert!(written.contains(r#""rest": [1.0, 2.5],"#), "{written}");
        assert!(
            written.contains(r#""rest": [[1.0, 2.0], [30.0, 40.0]]"#),
            "{written}"
        );
        assert!(written.contains(r#""offset": [[0.1234567, -2.0], [0.0, 0.0]]"#));
        assert!(written.contains("\n  \"handles\": [\n    {\n"), "{written}");
        assert_eq!(Project::from_json(&written).expect("reads back"), project);
    }

    #[test]
    fn carried_shapes_are_checked() {
        let with = |carried: &str| {
            Project::from_json(&format!(
                r#"{{"version":1,"handles":[{{"type":"point","rest":[1,2]}}],"carried":{carried}}}"#
            ))
        };
        for (carried, says) in [
            (r#"[{"rest":[[1,2]],"offset":[]}]"#, "the same vertices"),
            (
                r#"[{"rest":[[1,2]],"offset":[[1e300,0]]}]"#,
                "finite numbers",
            ),
            (
                r#"[{"rest":[[1,2]],"offset":[[0,0]]},{"rest":[[1,2]],"offset":[[0,0]]}]"#,
                "the picture carries two shapes",
            ),
            (
                r#"[{"part":1000,"rest":[[1,2]],"offset":[[0,0]]}]"#,
                "below 1000",
            ),
            (
                r#"[{"rest":[[1,2]],"offset":[[0,0]],"triangles":[]}]"#,
                "unknown field",
            ),
        ] {
            let error = with(carried).expect_err(carried);
            assert!(error.to_string().contains(says), "{carried}: {error}");
        }
        assert!(with(r#"[{"part":1,"rest":[[1,2]],"offset":[[0,0]]}]"#).is_ok());
    }

    #[test]
    fn too_many_handles_are_refused_naming_the_limit() {
        let point = HandleSpec::Point {
            rest: [1.0, 1.0],
            translate: [0.0, 0.0],
            rotate: 0.0,
            scale: 1.0,
            depth: 0,
        };
        let mut p = Project {
            handles: vec![point; MAX_HANDLES],
            ..Project::default()
        };
        assert!(p.validate(None).is_ok());
        p.handles.push(p.handles[0].clone());
        let err = p.validate(None).expect_err("one too many").to_string();
        assert!(
            err.contains("10001 handles; C2Warp is built for up to 10000 handles"),
            "{err}"
        );
    }
}
