//! Meshing for C2Warp: from an image to the triangle mesh that gets warped.
//!
//! The pipeline is image → [`Domain`] (polygons traced from the alpha channel, or the
//! full rectangle) → [`triangulate`] (a constrained Delaunay triangulation with
//! [spade], with handle points and bars as vertices and constraint edges) → [`Mesh`].
//! Meshes can be saved and loaded as Wavefront OBJ ([`Mesh::write_obj`],
//! [`Mesh::read_obj`]).
//!
//! Coordinates are image pixel coordinates throughout: origin at the top-left corner,
//! x to the right, y down; pixel `(x, y)` covers `[x, x+1] × [y, y+1]`. The crate knows
//! nothing of UIs, GPUs or warping weights.
//!
//! # Design choices
//! * **Outward tracing.** [`domain_from_image`] dilates the alpha mask by one pixel before
//!   tracing, so the outline runs about a pixel outside the visible pixels: a warped
//!   cut-out keeps its soft edge, and simplification (Douglas–Peucker, 0.75 px by
//!   default) can never cut off a visible pixel.
//! * **Nothing visible is dropped.** Every pixel with alpha > 0 (by default) is inside
//!   the domain. Content finer than the mesh spacing (specks, hair, text) keeps its exact
//!   outline while that costs at most half the target vertex count; beyond that it is
//!   merged into coarser cover polygons sized to the density ([`domain_for_density`]).
//! * **Connectivity.** Islands are 8-connected. The mask is then made well-composed
//!   (diagonal-only contacts are filled in), so 4- and 8-connectivity agree and every
//!   traced outline is a simple ring disjoint from the others; simplification keeps it so.
//! * **Triangulation.** Interior vertices come from a hexagonal lattice sized to
//!   [`MeshOptions::target_vertices`]; spade's Delaunay refinement then only repairs
//!   the band along the boundary and the constraints. See [`triangulate`].
//!
//! # Example
//! ```
//! use glam::DVec2;
//! use mesh::{Constraints, DomainOptions, MeshOptions, mesh_image};
//!
//! // A 100×80 image whose left half is transparent.
//! let img = image::RgbaImage::from_fn(100, 80, |x, _| {
//!     image::Rgba([200, 100, 50, if x < 50 { 0 } else { 255 }])
//! });
//! let bar = vec![DVec2::new(60.0, 10.0), DVec2::new(90.0, 70.0)];
//! let constraints = Constraints { points: &[], polylines: std::slice::from_ref(&bar) };
//! let opts = MeshOptions { target_vertices: 2_000, ..MeshOptions::default() };
//! let t = mesh_image(&img, &DomainOptions::default(), &opts, &constraints)?;
//! t.mesh.sanity_check()?;
//! assert!(!t.is_convex);
//! // The bar's ends are vertices at exactly the given coordinates.
//! assert_eq!(t.mesh.vertices[t.polyline_vertices[0][1] as usize], bar[1]);
//! # Ok::<(), mesh::MeshError>(())
//! ```

mod cover;
mod cut;
mod domain;
mod enclose;
mod error;
mod mesh;
mod obj;
mod segments;
mod simplify;
mod trace;
mod triangulate;

pub use cut::{clip_to_domain, split_along};
pub use domain::{Domain, DomainOptions, Polygon, domain_for_density, domain_from_image};
pub use enclose::{Coverage, Enclosure, enclosing_ring, enclosing_ring_of};
pub use error::MeshError;
pub use mesh::Mesh;
pub use triangulate::{
    Constraints, MAX_VERTICES_PER_PIXEL, MeshOptions, TriangulatedImage, mesh_image, triangulate,
};
