//! What the canvas hands the GPU each frame, and the paint callback that uploads what
//! changed and draws it with [`render::MeshView`].
//!
//! Every part carries a version; the callback resources remember the versions they
//! uploaded, so a drag re-uploads only the node transforms (24 bytes a node), or with
//! ARAP the deformed positions (8 bytes a vertex), and a new handle only the weights.
//!
//! For an LBC cage the mesh is the cage's inside with its compact rows, the nodes are
//! the cage's vertices (no linear part, the posed vertex as translation), and a
//! backdrop is drawn under it: the picture at rest with the rest cage's inside
//! cleared, as the export keeps the outside.

use std::sync::Arc;

use egui_wgpu::wgpu;
use glam::Vec2;
use image::RgbaImage;
use render::{Affine, MeshView, SkinnedMesh, ViewParams};

/// A value with the version it was made at (0: nothing yet).
#[derive(Default)]
pub struct Versioned<T> {
    /// Increases with every new value.
    pub version: u64,
    /// The value.
    pub value: Arc<T>,
}

impl<T> Clone for Versioned<T> {
    fn clone(&self) -> Self {
        Self {
            version: self.version,
            value: self.value.clone(),
        }
    }
}

/// The mesh with its weights, as the shader reads them.
#[derive(Default)]
pub struct MeshData {
    /// Rest positions (pixels).
    pub rest: Vec<Vec2>,
    /// Row offsets of the weights, one per vertex plus one.
    pub rows: Vec<u32>,
    /// Node of each weight.
    pub nodes: Vec<u32>,
    /// The weights.
    pub weights: Vec<f32>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// The picture's size in pixels.
    pub source_size: [u32; 2],
}

/// Everything the GPU draws, by version.
#[derive(Clone, Default)]
pub struct GpuFrame {
    /// The picture.
    pub image: Versioned<RgbaImage>,
    /// Mesh and weights.
    pub mesh: Versioned<MeshData>,
    /// Node transforms.
    pub pose: Versioned<Vec<Affine>>,
    /// Heat-map values per vertex.
    pub heat: Versioned<Vec<f32>>,
    /// Cell colours per vertex.
    pub cells: Versioned<Vec<[u8; 4]>>,
    /// Deformed positions per vertex, from a method that solves for them (ARAP);
    /// empty when the node transforms skin the mesh.
    pub positions: Versioned<Vec<Vec2>>,
    /// A picture drawn at rest under the mesh (the cage tool's view), if any.
    pub backdrop: Option<Versioned<RgbaImage>>,
}

/// The GPU side, kept in the renderer's callback resources.
pub struct SceneResources {
    view: MeshView,
    uploaded: [u64; 6],
    /// Draws [`GpuFrame::backdrop`]: the picture on a rectangle of two triangles.
    backdrop: MeshView,
    backdrop_uploaded: u64,
    /// The last upload failure, if any (shown in the status bar).
    pub error: Option<String>,
}

impl SceneResources {
    /// Pipelines for the window's target format (no multisampling, no depth buffer,
    /// as the editor configures eframe).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, format: wgpu::TextureFormat) -> Self {
        Self {
            view: MeshView::new(device, queue, format, 1),
            uploaded: [0; 6],
            backdrop: MeshView::new(device, queue, format, 1),
            backdrop_uploaded: 0,
            error: None,
        }
    }

    /// Uploads a new backdrop: its picture, on a rectangle of its size that one
    /// identity transform places.
    fn set_backdrop(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        picture: &RgbaImage,
    ) -> Result<(), render::RenderError> {
        let (w, h) = (picture.width() as f32, picture.height() as f32);
        let rest = [
            Vec2::new(0.0, 0.0),
            Vec2::new(w, 0.0),
            Vec2::new(w, h),
            Vec2::new(0.0, h),
        ];
        let mesh = SkinnedMesh {
            rest: &rest,
            rows: &[0, 1, 2, 3, 4],
            nodes: &[0; 4],
            weights: &[1.0; 4],
            triangles: &[[0, 1, 2], [0, 2, 3]],
        };
        self.backdrop.set_texture(device, queue, picture);
        let identity: Affine = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0];
        self.backdrop.set_mesh(
            device,
            &mesh,
            &[identity],
            [picture.width(), picture.height()],
        )
    }

    fn update(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, frame: &GpuFrame) {
        let versions = [
            frame.image.version,
            frame.mesh.version,
            frame.pose.version,
            frame.heat.version,
            frame.cells.version,
            frame.positions.version,
        ];
        if versions[0] != self.uploaded[0] {
            self.view.set_texture(device, queue, &frame.image.value);
        }
        let mesh_changed = versions[1] != self.uploaded[1];
        let mut result = Ok(());
        if mesh_changed {
            let m = &frame.mesh.value;
            let mesh = SkinnedMesh {
                rest: &m.rest,
                rows: &m.rows,
                nodes: &m.nodes,
                weights: &m.weights,
                triangles: &m.triangles,
            };
            result = self
                .view
                .set_mesh(device, &mesh, &frame.pose.value, m.source_size);
        } else if versions[2] != self.uploaded[2] {
            result = self.view.set_pose(queue, &frame.pose.value);
        }
        let pose_changed = mesh_changed || versions[2] != self.uploaded[2];
        if result.is_ok()
            && (pose_changed || versions[5] != self.uploaded[5])
            && !frame.positions.value.is_empty()
        {
            result = self.view.set_positions(queue, &frame.positions.value);
        }
        if result.is_ok()
            && (mesh_changed || versions[3] != self.uploaded[3])
            && !frame.heat.value.is_empty()
        {
            result = self.view.set_heat(queue, &frame.heat.value);
        }
        if result.is_ok()
            && (mesh_changed || versions[4] != self.uploaded[4])
            && !frame.cells.value.is_empty()
        {
            result = self.view.set_cells(queue, &frame.cells.value);
        }
        if result.is_ok()
            && let Some(backdrop) = &frame.backdrop
            && backdrop.version != self.backdrop_uploaded
        {
            result = self.set_backdrop(device, queue, &backdrop.value);
            self.backdrop_uploaded = backdrop.version;
        }
        self.error = result.err().map(|e| e.to_string());
        self.uploaded = versions;
    }
}

impl GpuFrame {
    /// Draws this frame as the canvas does (backdrop, then the mesh; no overlays), one
    /// image pixel to one output pixel, into an offscreen target of `gpu` covering
    /// `frame` (the picture's rectangle, or the grown canvas of an export): the view at
    /// full resolution, to compare with an export.
    ///
    /// # Errors
    /// An empty frame, or a GPU failure.
    pub fn draw_offscreen(
        &self,
        gpu: &render::GpuContext,
        frame: pipeline::Frame,
    ) -> Result<RgbaImage, render::RenderError> {
        let (w, h) = (frame.width, frame.height);
        if w == 0 || h == 0 {
            return Err(render::RenderError::OutputTooLarge {
                width: w,
                height: h,
            });
        }
        let format = wgpu::TextureFormat::Rgba8Unorm;
        let mut scene = SceneResources::new(gpu.device(), gpu.queue(), format);
        scene.update(gpu.device(), gpu.queue(), self);
        if let Some(e) = &scene.error {
            return Err(render::RenderError::Gpu(e.clone()));
        }
        // Image pixels to clip space, y down: the frame's corner to (−1, 1).
        let (fw, fh) = (w as f32, h as f32);
        let [ox, oy] = frame.origin.map(|o| o as f32);
        let params = ViewParams {
            scale: [2.0 / fw, -2.0 / fh],
            offset: [-1.0 - 2.0 * ox / fw, 1.0 + 2.0 * oy / fh],
            overlay: render::Overlay::None,
            show_folds: false,
            wireframe: false,
        };
        scene.view.prepare(gpu.queue(), &params);
        if self.backdrop.is_some() {
            scene.backdrop.prepare(gpu.queue(), &params);
        }
        gpu.offscreen(w, h, |pass| {
            if self.backdrop.is_some() {
                scene.backdrop.paint(pass, false);
            }
            scene.view.paint(pass, false);
        })
    }
}

/// The canvas' paint callback.
pub struct MeshCallback {
    /// What to draw.
    pub frame: GpuFrame,
    /// Where and how.
    pub params: ViewParams,
}

impl egui_wgpu::CallbackTrait for MeshCallback {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &egui_wgpu::ScreenDescriptor,
        _encoder: &mut wgpu::CommandEncoder,
        resources: &mut egui_wgpu::CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        if let Some(scene) = resources.get_mut::<SceneResources>() {
            scene.update(device, queue, &self.frame);
            scene.view.prepare(queue, &self.params);
            if self.frame.backdrop.is_some() {
                let plain = ViewParams {
                    overlay: render::Overlay::None,
                    show_folds: false,
                    wireframe: false,
                    ..self.params
                };
                scene.backdrop.prepare(queue, &plain);
            }
        }
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        pass: &mut wgpu::RenderPass<'static>,
        resources: &egui_wgpu::CallbackResources,
    ) {
        if let Some(scene) = resources.get::<SceneResources>()
            && scene.error.is_none()
        {
            if self.frame.backdrop.is_some() {
                scene.backdrop.paint(pass, false);
            }
            scene.view.paint(pass, self.params.wireframe);
        }
    }
}
