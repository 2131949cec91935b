//! The interactive view: the textured mesh drawn into someone else's render pass (an
//! editor's window), skinned in the vertex shader so a drag uploads only node
//! transforms, with optional overlays: a heat map with isolines, flat-coloured cells,
//! the wireframe, and fold-overs (triangles whose orientation flipped) tinted red.
//!
//! It takes a device, a queue and a render pass, not a window or a UI toolkit: the
//! editor wraps it in its paint callback, and tests draw it offscreen.

use glam::Vec2;
use image::RgbaImage;
use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::gpu::{
    Affine, SKIN_WGSL, SkinnedMesh, pack_transforms, picture_bind_group, skin_bind_group,
};

/// What to tint the mesh with, besides the texture.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Overlay {
    /// The image alone.
    #[default]
    None,
    /// The per-vertex scalar of [`MeshView::set_heat`] in a colour ramp, isolines every
    /// tenth.
    Heat,
    /// The per-vertex colours of [`MeshView::set_cells`], one colour per triangle (its
    /// first vertex's).
    Cells,
}

/// Where the mesh goes in the render pass's viewport, and how it is tinted.
///
/// A point `p` in image pixels lands at `p * scale + offset` in normalised device
/// coordinates of the viewport (x right, y up, −1…1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewParams {
    /// Image pixels to device coordinates, per axis.
    pub scale: [f32; 2],
    /// Device coordinates of the image origin.
    pub offset: [f32; 2],
    /// The overlay.
    pub overlay: Overlay,
    /// Tint triangles whose orientation flipped.
    pub show_folds: bool,
    /// Draw the mesh edges too.
    pub wireframe: bool,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Uniform {
    scale: [f32; 2],
    offset: [f32; 2],
    mode: u32,
    folds: u32,
    /// 1: vertices sit at the uploaded deformed positions instead of being skinned.
    positioned: u32,
    _pad: u32,
    line: [f32; 4],
}

const VIEW_WGSL: &str = r"
struct View { scale: vec2<f32>, offset: vec2<f32>, mode: u32, folds: u32, positioned: u32, pad: u32, line: vec4<f32> };
@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var source: texture_2d<f32>;
@group(0) @binding(2) var linear: sampler;

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) heat: f32,
    @location(2) @interpolate(flat) cell: vec4<f32>,
};

fn place(p: vec2<f32>) -> vec4<f32> {
    return vec4<f32>(p * view.scale + view.offset, 0.0, 1.0);
}

// Where a vertex goes: blended by its nodes' transforms (C² weights), or where a
// method that solves for positions (ARAP) put it.
fn moved(index: u32, rest: vec2<f32>, deformed: vec2<f32>) -> vec2<f32> {
    if view.positioned == 1u {
        return deformed;
    }
    return skin(index, rest);
}

@vertex
fn vs(
    @builtin(vertex_index) index: u32,
    @location(0) rest: vec2<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) heat: f32,
    @location(3) cell: vec4<f32>,
    @location(4) deformed: vec2<f32>,
) -> Out {
    var out: Out;
    out.clip = place(moved(index, rest, deformed));
    out.uv = uv;
    out.heat = heat;
    out.cell = cell;
    return out;
}

// A blue-to-yellow ramp that stays readable over any picture.
fn ramp(t: f32) -> vec3<f32> {
    let c0 = vec3<f32>(0.05, 0.03, 0.53);
    let c1 = vec3<f32>(0.80, 0.28, 0.47);
    let c2 = vec3<f32>(0.94, 0.98, 0.13);
    if t < 0.5 {
        return mix(c0, c1, t * 2.0);
    }
    return mix(c1, c2, t * 2.0 - 1.0);
}

@fragment
fn fs(in: Out, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    var color = textureSample(source, linear, in.uv);
    // Derivatives first: they need uniform control flow.
    let steps = in.heat * 10.0;
    let width = max(fwidth(steps), 1e-6);
    // Isolines at the tenths strictly between 0 and 1: the plateaus where the weight
    // is exactly 0 or 1 are not lines.
    let inside = select(0.0, 1.0, in.heat > 0.001 && in.heat < 0.999);
    let iso = inside * (1.0 - clamp(abs(fract(steps + 0.5) - 0.5) / width, 0.0, 1.0));
    if view.mode == 1u {
        let a = max(color.a, 0.35);
        var tint = ramp(clamp(in.heat, 0.0, 1.0));
        tint = mix(tint, vec3<f32>(1.0, 1.0, 1.0), iso * 0.9);
        color = vec4<f32>(mix(color.rgb, tint * a, 0.7), a);
    } else if view.mode == 2u {
        let a = max(color.a, 0.35);
        color = vec4<f32>(mix(color.rgb, in.cell.rgb * a, 0.55), a);
    }
    if view.folds == 1u && !front {
        let a = max(color.a, 0.6);
        color = vec4<f32>(mix(color.rgb, vec3<f32>(0.9, 0.05, 0.05) * a, 0.7), a);
    }
    return color;
}

@vertex
fn vs_line(
    @builtin(vertex_index) index: u32,
    @location(0) rest: vec2<f32>,
    @location(4) deformed: vec2<f32>,
) -> @builtin(position) vec4<f32> {
    return place(moved(index, rest, deformed));
}

@fragment
fn fs_line() -> @location(0) vec4<f32> {
    return view.line;
}
";

/// One vertex of the view's mesh: rest position (pixels), texture coordinate, heat,
/// cell colour.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ViewVertex {
    rest: [f32; 2],
    uv: [f32; 2],
}

/// The mesh on the GPU.
struct GpuMesh {
    vertices: wgpu::Buffer,
    heat: wgpu::Buffer,
    cells: wgpu::Buffer,
    /// Deformed positions, read instead of skinning in positioned mode.
    deformed: wgpu::Buffer,
    triangles: wgpu::Buffer,
    triangle_indices: u32,
    edges: wgpu::Buffer,
    edge_indices: u32,
    transforms: wgpu::Buffer,
    nodes: usize,
    skin: wgpu::BindGroup,
    vertex_count: usize,
}

/// Draws a skinned textured mesh into a render pass of the given target format.
pub struct MeshView {
    fill: wgpu::RenderPipeline,
    lines: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    skin_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    uniform: wgpu::Buffer,
    texture: wgpu::BindGroup,
    mesh: Option<GpuMesh>,
    /// Whether the last pose came as positions ([`MeshView::set_positions`]) rather
    /// than node transforms.
    positioned: std::sync::atomic::AtomicBool,
}

impl MeshView {
    /// Pipelines for render passes into `format` with `samples` samples per pixel (1
    /// without multisampling), no depth buffer, premultiplied-alpha blending. Starts
    /// with a 1×1 transparent texture and no mesh.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        format: wgpu::TextureFormat,
        samples: u32,
    ) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mesh view"),
            source: wgpu::ShaderSource::Wgsl(format!("{SKIN_WGSL}{VIEW_WGSL}").into()),
        });
        let entry = |binding, visibility, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty,
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mesh view"),
            entries: &[
                entry(
                    0,
                    wgpu::ShaderStages::VERTEX_FRAGMENT,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                ),
                entry(
                    1,
                    wgpu::ShaderStages::FRAGMENT,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                ),
                entry(
                    2,
                    wgpu::ShaderStages::FRAGMENT,
                    wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                ),
            ],
        });
        let storage = |binding| {
            entry(
                binding,
                wgpu::ShaderStages::VERTEX,
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
            )
        };
        let skin_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mesh view skin"),
            entries: &[storage(0), storage(1), storage(2)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mesh view"),
            bind_group_layouts: &[Some(&layout), Some(&skin_layout)],
            immediate_size: 0,
        });
        let pipeline = |topology, fragment: &str, all_attributes: bool| {
            let geometry = wgpu::vertex_attr_array![0 => Float32x2, 1 => Float32x2];
            let heat = wgpu::vertex_attr_array![2 => Float32];
            let cells = wgpu::vertex_attr_array![3 => Unorm8x4];
            let deformed = wgpu::vertex_attr_array![4 => Float32x2];
            let buffer = |stride, attributes| {
                Some(wgpu::VertexBufferLayout {
                    array_stride: stride,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes,
                })
            };
            let mut buffers = vec![buffer(16, &geometry[..])];
            if all_attributes {
                buffers.push(buffer(4, &heat[..]));
                buffers.push(buffer(4, &cells[..]));
            }
            buffers.push(buffer(8, &deformed[..]));
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("mesh view"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(if all_attributes { "vs" } else { "vs_line" }),
                    compilation_options: Default::default(),
                    buffers: &buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology,
                    // See `set_mesh`: rest triangles are front facing.
                    front_face: wgpu::FrontFace::Cw,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: None,
                multisample: wgpu::MultisampleState {
                    count: samples.max(1),
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let fill = pipeline(wgpu::PrimitiveTopology::TriangleList, "fs", true);
        let lines = pipeline(wgpu::PrimitiveTopology::LineList, "fs_line", false);
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("mesh view"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("mesh view"),
            size: std::mem::size_of::<Uniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let empty = RgbaImage::new(1, 1);

        let texture = picture_bind_group(device, queue, &layout, &uniform, &sampler, &empty);
        Self {
            fill,
            lines,
            layout,
            skin_layout,
            sampler,
            uniform,
            texture,
            mesh: None,
            positioned: std::sync::atomic::AtomicBool::new(false),
        }
    }

    /// Uploads the picture, scaled down (keeping its aspect) if it exceeds the device's
    /// largest texture. Mesh rest positions keep addressing it in source pixels of
    /// `source_size`.
    pub fn set_texture(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, image: &RgbaImage) {
        let max = device.limits().max_texture_dimension_2d;
        let (w, h) = image.dimensions();
        let fitted;
        let image = if w > max || h > max {
            let s = f64::from(max) / f64::from(w.max(h));
            let (fw, fh) = (
                ((f64::from(w) * s) as u32).clamp(1, max),
                ((f64::from(h) * s) as u32).clamp(1, max),
            );
            fitted = image::imageops::resize(image, fw, fh, image::imageops::FilterType::Triangle);
            &fitted
        } else {
            image
        };
        self.texture = picture_bind_group(
            device,
            queue,
            &self.layout,
            &self.uniform,
            &self.sampler,
            image,
        );
    }

    /// Uploads a mesh: rest positions, texture coordinates (rest / `source_size`),
    /// weight rows, triangles and edges, and the initial node transforms. Heat and cell
    /// colours start at zero.
    ///
    /// # Errors
    /// An inconsistent mesh (see [`SkinnedMesh`]), or a mesh or transform table the
    /// device cannot hold.
    pub fn set_mesh(
        &mut self,
        device: &wgpu::Device,
        mesh: &SkinnedMesh,
        transforms: &[Affine],
        source_size: [u32; 2],
    ) -> Result<(), RenderError> {
        mesh.validate(transforms)?;
        let size = [source_size[0].max(1) as f32, source_size[1].max(1) as f32];
        let mut vertices: Vec<ViewVertex> = mesh
            .rest
            .iter()
            .map(|p| ViewVertex {
                rest: p.to_array(),
                uv: [p.x / size[0], p.y / size[1]],
            })
            .collect();
        if vertices.is_empty() {
            // Buffers may not be empty; an empty mesh draws nothing (see `paint`).
            vertices.push(ViewVertex {
                rest: [0.0; 2],
                uv: [0.0; 2],
            });
        }
        // Every rest triangle gets a positive signed area in image coordinates (y
        // down), which the y flip of `ViewParams::scale` makes clockwise in device
        // coordinates: the pipelines' front face. A fold-over shows its back.
        let triangles: Vec<u32> = mesh
            .triangles
            .iter()
            .flat_map(|&[a, b, c]| {
                let (pa, pb, pc) = (
                    mesh.rest[a as usize],
                    mesh.rest[b as usize],
                    mesh.rest[c as usize],
                );
                if (pb - pa).perp_dot(pc - pa) >= 0.0 {
                    [a, b, c]
                } else {
                    [a, c, b]
                }
            })
            .collect();
        let mut edges: Vec<[u32; 2]> = mesh
            .triangles
            .iter()
            .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let max_bytes = device.limits().max_storage_buffer_binding_size as usize;
        let entries = mesh.packed_entries();
        let packed = pack_transforms(transforms);
        if entries.len() * 8 > max_bytes || packed.len() * 16 > max_bytes {
            return Err(RenderError::Gpu(format!(
                "the mesh's weights ({} entries) exceed the device's storage buffer size",
                entries.len()
            )));
        }
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let storage = wgpu::BufferUsages::STORAGE;
        let rows = init("rows", bytemuck::cast_slice(mesh.rows), storage);
        let entries = init("entries", bytemuck::cast_slice(&entries), storage);
        let transform_buffer = init(
            "transforms",
            bytemuck::cast_slice(&packed),
            storage | wgpu::BufferUsages::COPY_DST,
        );
        let skin = skin_bind_group(
            device,
            &self.skin_layout,
            [&rows, &entries, &transform_buffer],
        );
        let n = mesh.rest.len();
        let per_vertex = wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST;
        self.mesh = Some(GpuMesh {
            vertices: init("view vertices", bytemuck::cast_slice(&vertices), per_vertex),
            heat: init(
                "heat",
                bytemuck::cast_slice(&vec![0f32; n.max(1)]),
                per_vertex,
            ),
            cells: init(
                "cells",
                bytemuck::cast_slice(&vec![0u32; n.max(1)]),
                per_vertex,
            ),
            deformed: init(
                "deformed",
                bytemuck::cast_slice(&nonempty_vec2(mesh.rest.to_vec())),
                per_vertex,
            ),
            triangles: init(
                "triangles",
                bytemuck::cast_slice(&nonempty_u32(triangles.clone())),
                wgpu::BufferUsages::INDEX,
            ),
            triangle_indices: triangles.len() as u32,
            edges: init(
                "edges",
                bytemuck::cast_slice(&nonempty_u32(edges.as_flattened().to_vec())),
                wgpu::BufferUsages::INDEX,
            ),
            edge_indices: (edges.len() * 2) as u32,
            transforms: transform_buffer,
            nodes: transforms.len(),
            skin,
            vertex_count: n,
        });
        self.set_positioned(false);
        Ok(())
    }

    fn set_positioned(&self, positioned: bool) {
        self.positioned
            .store(positioned, std::sync::atomic::Ordering::Relaxed);
    }

    /// Uploads deformed positions (pixels, one per vertex: 8 bytes a vertex) for a
    /// method that solves for positions rather than weights; they are drawn until the
    /// next [`MeshView::set_pose`] or [`MeshView::set_mesh`].
    ///
    /// # Errors
    /// No mesh, not one position per vertex, or non-finite values.
    pub fn set_positions(
        &self,
        queue: &wgpu::Queue,
        positions: &[Vec2],
    ) -> Result<(), RenderError> {
        let mesh = self.per_vertex(positions.len(), "positions")?;
        if !positions.iter().all(|p| p.is_finite()) {
            return Err(RenderError::Gpu("non-finite deformed positions".into()));
        }
        let packed: Vec<[f32; 2]> = positions.iter().map(|p| p.to_array()).collect();
        queue.write_buffer(&mesh.deformed, 0, bytemuck::cast_slice(&packed));
        self.set_positioned(true);
        Ok(())
    }

    /// Whether a mesh has been uploaded.
    pub fn has_mesh(&self) -> bool {
        self.mesh.is_some()
    }

    /// Uploads new node transforms (a new pose) for the current mesh.
    ///
    /// # Errors
    /// No mesh, a transform count different from the mesh's, or non-finite values.
    pub fn set_pose(&self, queue: &wgpu::Queue, transforms: &[Affine]) -> Result<(), RenderError> {
        let mesh = self.mesh.as_ref().ok_or_else(|| no_mesh("pose"))?;
        if transforms.len() != mesh.nodes || !transforms.iter().flatten().all(|x| x.is_finite()) {
            return Err(RenderError::Gpu(format!(
                "{} transforms for a mesh of {} nodes, or non-finite values",
                transforms.len(),
                mesh.nodes
            )));
        }
        queue.write_buffer(
            &mesh.transforms,
            0,
            bytemuck::cast_slice(&pack_transforms(transforms)),
        );
        self.set_positioned(false);
        Ok(())
    }

    /// Per-vertex scalars for [`Overlay::Heat`] (0…1 across the ramp).
    ///
    /// # Errors
    /// No mesh, or not one value per vertex.
    pub fn set_heat(&self, queue: &wgpu::Queue, values: &[f32]) -> Result<(), RenderError> {
        let mesh = self.per_vertex(values.len(), "heat")?;
        queue.write_buffer(&mesh.heat, 0, bytemuck::cast_slice(values));
        Ok(())
    }

    /// Per-vertex RGBA colours for [`Overlay::Cells`].
    ///
    /// # Errors
    /// No mesh, or not one colour per vertex.
    pub fn set_cells(&self, queue: &wgpu::Queue, colors: &[[u8; 4]]) -> Result<(), RenderError> {
        let mesh = self.per_vertex(colors.len(), "cell colours")?;
        queue.write_buffer(&mesh.cells, 0, bytemuck::cast_slice(colors));
        Ok(())
    }

    fn per_vertex(&self, len: usize, what: &str) -> Result<&GpuMesh, RenderError> {
        let mesh = self.mesh.as_ref().ok_or_else(|| no_mesh(what))?;
        if len != mesh.vertex_count || len == 0 {
            return Err(RenderError::Gpu(format!(
                "{len} {what} for a mesh of {} vertices",
                mesh.vertex_count
            )));
        }
        Ok(mesh)
    }

    /// Writes the view parameters; call before the render pass that [`MeshView::paint`]
    /// records into.
    pub fn prepare(&self, queue: &wgpu::Queue, params: &ViewParams) {
        let uniform = Uniform {
            scale: params.scale,
            offset: params.offset,
            mode: match params.overlay {
                Overlay::None => 0,
                Overlay::Heat => 1,
                Overlay::Cells => 2,
            },
            folds: u32::from(params.show_folds),
            positioned: u32::from(self.positioned.load(std::sync::atomic::Ordering::Relaxed)),
            _pad: 0,
            line: [0.0, 0.0, 0.0, 0.25],
        };
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
    }

    /// Records the draw calls (mesh, then wireframe if asked) into `pass`. A mesh
    /// without vertices draws nothing.
    pub fn paint(&self, pass: &mut wgpu::RenderPass<'_>, wireframe: bool) {
        let Some(mesh) = self.mesh.as_ref().filter(|m| m.vertex_count > 0) else {
            return;
        };
        pass.set_bind_group(0, &self.texture, &[]);
        pass.set_bind_group(1, &mesh.skin, &[]);
        pass.set_vertex_buffer(0, mesh.vertices.slice(..));
        if mesh.triangle_indices > 0 {
            pass.set_pipeline(&self.fill);
            pass.set_vertex_buffer(1, mesh.heat.slice(..));
            pass.set_vertex_buffer(2, mesh.cells.slice(..));
            pass.set_vertex_buffer(3, mesh.deformed.slice(..));
            pass.set_index_buffer(mesh.triangles.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..mesh.triangle_indices, 0, 0..1);
        }
        if wireframe && mesh.edge_indices > 0 {
            pass.set_pipeline(&self.lines);
            pass.set_vertex_buffer(1, mesh.deformed.slice(..));
            pass.set_index_buffer(mesh.edges.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..mesh.edge_indices, 0, 0..1);
        }
    }
}

fn no_mesh(what: &str) -> RenderError {
    RenderError::Gpu(format!("no mesh to set the {what} of"))
}

/// The points of `v` as arrays, or one zero point if it is empty (buffers may not be
/// empty).
fn nonempty_vec2(v: Vec<Vec2>) -> Vec<[f32; 2]> {
    if v.is_empty() {
        return vec![[0.0; 2]];
    }
    v.iter().map(|p| p.to_array()).collect()
}

fn nonempty_u32(mut v: Vec<u32>) -> Vec<u32> {
    if v.is_empty() {
        v.extend([0, 0, 0]);
    }
    v
}
