//! The same warp as [`crate::warp_cpu`], drawn by the GPU through wgpu into an
//! offscreen texture and read back. Works on a software adapter (Mesa lavapipe or
//! llvmpipe) when there is no GPU.

use glam::Vec2;
use image::RgbaImage;
use wgpu::util::DeviceExt;

use crate::error::RenderError;
use crate::mesh::WarpMesh;

/// A wgpu device and queue for offscreen work.
pub struct GpuContext {
    device: wgpu::Device,
    queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    pipeline: wgpu::RenderPipeline,
    skinned: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    skin_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
}

/// One vertex: where it is drawn (output pixels) and where it samples (source pixels).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Vertex {
    position: [f32; 2],
    rest: [f32; 2],
}

/// Output and texture sizes, in pixels.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Sizes {
    output: [f32; 2],
    texture: [f32; 2],
}

/// What both shaders share: the bindings of group 0, placing a vertex given in output
/// pixels with its rest position as texture coordinates, and sampling the texture.
const COMMON_WGSL: &str = r"
struct Sizes { output: vec2<f32>, texture: vec2<f32> };
@group(0) @binding(0) var<uniform> sizes: Sizes;
@group(0) @binding(1) var source: texture_2d<f32>;
@group(0) @binding(2) var linear: sampler;

struct Out { @builtin(position) clip: vec4<f32>, @location(0) uv: vec2<f32> };

fn place(position: vec2<f32>, rest: vec2<f32>) -> Out {
    var out: Out;
    let ndc = position / sizes.output * 2.0 - vec2<f32>(1.0, 1.0);
    out.clip = vec4<f32>(ndc.x, -ndc.y, 0.0, 1.0);
    out.uv = rest / sizes.texture;
    return out;
}

@fragment
fn fs(in: Out) -> @location(0) vec4<f32> {
    return textureSample(source, linear, in.uv);
}
";

/// Vertices arrive already deformed.
const PLAIN_VERTEX_WGSL: &str = r"
@vertex
fn vs(@location(0) position: vec2<f32>, @location(1) rest: vec2<f32>) -> Out {
    return place(position, rest);
}
";

/// Linear blend skinning: the vertex at `index` moved by the blend of its nodes' affine
/// transforms, read from storage buffers (group 1), so a new pose uploads only the
/// transforms; a vertex with an empty row stays at rest. Shared with the on-screen view.
pub(crate) const SKIN_WGSL: &str = r"
@group(1) @binding(0) var<storage, read> rows: array<u32>;
@group(1) @binding(1) var<storage, read> entries: array<vec2<u32>>;
@group(1) @binding(2) var<storage, read> transforms: array<vec4<f32>>;

fn skin(index: u32, rest: vec2<f32>) -> vec2<f32> {
    // A vertex no node reaches (a rig without handles) stays where it is.
    if rows[index] == rows[index + 1u] {
        return rest;
    }
    var position = vec2<f32>(0.0, 0.0);
    for (var i = rows[index]; i < rows[index + 1u]; i = i + 1u) {
        let entry = entries[i];
        let w = bitcast<f32>(entry.y);
        let linear_part = transforms[2u * entry.x];
        let shift = transforms[2u * entry.x + 1u];
        position += w * (linear_part.xy * rest.x + linear_part.zw * rest.y + shift.xy);
    }
    return position;
}
";

/// Vertices move by [`SKIN_WGSL`].
const SKINNED_VERTEX_WGSL: &str = r"
@vertex
fn vs(@builtin(vertex_index) index: u32, @location(0) rest: vec2<f32>) -> Out {
    return place(skin(index, rest), rest);
}
";

/// A mesh whose vertices are moved by blending node transforms on the GPU.
pub struct SkinnedMesh<'a> {
    /// Rest positions in source pixels (also the texture coordinates).
    pub rest: &'a [Vec2],
    /// Row `v` of the weights is `nodes[rows[v]..rows[v + 1]]` (length: vertices + 1).
    pub rows: &'a [u32],
    /// Node index of each weight.
    pub nodes: &'a [u32],
    /// The weights (each row sums to one).
    pub weights: &'a [f32],
    /// Triangles as vertex index triples.
    pub triangles: &'a [[u32; 3]],
}

impl SkinnedMesh<'_> {
    /// Checks that rows, nodes, weights and triangles refer to one another consistently
    /// and hold finite values, for `transforms` node transforms.
    pub(crate) fn validate(&self, transforms: &[Affine]) -> Result<(), RenderError> {
        let n = self.rest.len();
        let bad = |what: &str| RenderError::Gpu(format!("invalid skinned mesh: {what}"));
        if self.rows.len() != n + 1 || self.nodes.len() != self.weights.len() {
            return Err(bad("row table lengths"));
        }
        if self.rows.windows(2).any(|w| w[0] > w[1]) || self.rows[n] as usize != self.nodes.len() {
            return Err(bad("row offsets"));
        }
        if self.nodes.iter().any(|&k| k as usize >= transforms.len()) {
            return Err(bad("a node without a transform"));
        }
        if self.triangles.iter().flatten().any(|&v| v as usize >= n) {
            return Err(bad("a triangle index out of range"));
        }
        if !transforms
            .iter()
            .flatten()
            .chain(self.weights)
            .all(|x| x.is_finite())
            || !self.rest.iter().all(|p| p.is_finite())
        {
            return Err(bad("non-finite values"));
        }
        Ok(())
    }

    /// The weight entries as the shader reads them: `(node, weight bits)`, never empty
    /// (storage buffers may not be).
    pub(crate) fn packed_entries(&self) -> Vec<[u32; 2]> {
        let entries = self
            .nodes
            .iter()
            .zip(self.weights)
            .map(|(&k, &w)| [k, w.to_bits()])
            .collect();
        nonempty(entries, [0, 0])
    }
}

/// Node transforms as the shader reads them: two `vec4`s each, never empty.
pub(crate) fn pack_transforms(transforms: &[Affine]) -> Vec<[f32; 4]> {
    let packed = transforms
        .iter()
        .flat_map(|t| [[t[0], t[1], t[2], t[3]], [t[4], t[5], 0.0, 0.0]])
        .collect();
    nonempty(packed, [0.0; 4])
}

/// Texels with their colour multiplied by alpha, so filtering does not bleed the colour
/// of transparent texels.
pub(crate) fn premultiply(texture: &RgbaImage) -> Vec<u8> {
    texture
        .pixels()
        .flat_map(|p| {
            let a = u16::from(p[3]);
            let m = |c: u8| ((u16::from(c) * a + 127) / 255) as u8;
            [m(p[0]), m(p[1]), m(p[2]), p[3]]
        })
        .collect()
}

/// An affine transform of pixel coordinates, `x ↦ A x + t`, as
/// `[a₀₀, a₁₀, a₀₁, a₁₁, t₀, t₁]` (the columns of `A`, then `t`).
pub type Affine = [f32; 6];

const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

impl GpuContext {
    /// Opens the first adapter wgpu offers (a software one if that is all there is).
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] when no adapter or device can be had.
    pub fn new() -> Result<Self, RenderError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let options = |fallback| wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: fallback,
            compatible_surface: None,
            apply_limit_buckets: false,
        };
        let adapter = pollster::block_on(instance.request_adapter(&options(false)))
            .or_else(|_| pollster::block_on(instance.request_adapter(&options(true))))
            .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("c2warp offscreen"),
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            ..Default::default()
        }))
        .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("warp"),
            source: wgpu::ShaderSource::Wgsl(format!("{COMMON_WGSL}{PLAIN_VERTEX_WGSL}").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("warp"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let skin_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("skin"),
            entries: &[storage(0), storage(1), storage(2)],
        });
        let pipeline = make_pipeline(
            &device,
            &module,
            &[Some(&layout)],
            &[wgpu::VertexFormat::Float32x2, wgpu::VertexFormat::Float32x2],
        );
        let skinned_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("skinned warp"),
            source: wgpu::ShaderSource::Wgsl(
                format!("{COMMON_WGSL}{SKIN_WGSL}{SKINNED_VERTEX_WGSL}").into(),
            ),
        });
        let skinned = make_pipeline(
            &device,
            &skinned_module,
            &[Some(&layout), Some(&skin_layout)],
            &[wgpu::VertexFormat::Float32x2],
        );
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("warp"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            device,
            queue,
            info: adapter.get_info(),
            pipeline,
            skinned,
            layout,
            skin_layout,
            sampler,
        })
    }

    /// The adapter in use (name, backend, device type).
    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// Draws `mesh` textured with `texture` into a `width × height` image, like
    /// [`crate::warp_cpu`]: premultiplied bilinear sampling clamped to the edge, later
    /// triangles composited over earlier ones ("over" in premultiplied alpha),
    /// uncovered pixels transparent.
    ///
    /// # Errors
    /// An invalid mesh, an empty texture, or a size the device cannot hold.
    pub fn warp(
        &self,
        texture: &RgbaImage,
        mesh: &WarpMesh,
        width: u32,
        height: u32,
    ) -> Result<RgbaImage, RenderError> {
        mesh.validate()?;
        let vertices: Vec<Vertex> = mesh
            .triangles
            .iter()
            .flat_map(|t| t.map(|v| v as usize))
            .map(|v| Vertex {
                position: clamp(mesh.deformed[v]),
                rest: mesh.rest[v].to_array(),
            })
            .collect();
        let vertex_buffer = self.buffer(
            "vertices",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
        );
        self.draw(texture, width, height, |pass| {
            pass.set_pipeline(&self.pipeline);
            pass.set_vertex_buffer(0, vertex_buffer.slice(..));
            pass.draw(0..vertices.len() as u32, 0..1);
        })
    }

    /// Draws `mesh` with every vertex moved by the blend of its nodes' `transforms`
    /// (computed in the vertex shader), textured with `texture`: the same picture as
    /// [`GpuContext::warp`] of the blended positions.
    ///
    /// # Errors
    /// Rows or triangles that refer to missing vertices, nodes or weights; non-finite
    /// transforms or weights; an empty texture; a size the device cannot hold.
    pub fn warp_skinned(
        &self,
        texture: &RgbaImage,
        mesh: &SkinnedMesh,
        transforms: &[Affine],
        width: u32,
        height: u32,
    ) -> Result<RgbaImage, RenderError> {
        mesh.validate(transforms)?;
        let entries = mesh.packed_entries();
        let packed = pack_transforms(transforms);
        let storage = wgpu::BufferUsages::STORAGE;
        // Storage buffers may not be empty.
        let rows = self.buffer("rows", bytemuck::cast_slice(mesh.rows), storage);
        let entries = self.buffer("entries", bytemuck::cast_slice(&entries), storage);
        let packed = self.buffer("transforms", bytemuck::cast_slice(&packed), storage);
        let skin = skin_bind_group(&self.device, &self.skin_layout, [&rows, &entries, &packed]);
        let rest: Vec<[f32; 2]> = mesh.rest.iter().map(|p| p.to_array()).collect();
        let vertex_buffer = self.buffer(
            "rest",
            bytemuck::cast_slice(&rest),
            wgpu::BufferUsages::VERTEX,
        );
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let index_buffer = self.buffer(
            "indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        );
        self.draw(texture, width, height, |pass| {
            pass.set_pipeline(&self.skinned);
            pass.set_bind_group(1, &skin, &[]);
            pass.set_vertex_buffer(0, vertex_buffer.slice(..));
            pass.set_index_buffer(index_buffer.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..indices.len() as u32, 0, 0..1);
        })
    }

    fn buffer(&self, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
    }

    /// Uploads the texture, runs `record` in a render pass into a `width × height`
    /// target cleared to transparent, and reads the target back, unpremultiplied.
    fn draw(
        &self,
        texture: &RgbaImage,
        width: u32,
        height: u32,
        record: impl FnOnce(&mut wgpu::RenderPass<'_>),
    ) -> Result<RgbaImage, RenderError> {
        if texture.width() == 0 || texture.height() == 0 {
            return Err(RenderError::EmptyTexture {
                width: texture.width(),
                height: texture.height(),
            });
        }
        let max = self.device.limits().max_texture_dimension_2d;
        if width == 0
            || height == 0
            || width > max
            || height > max
            || texture.width() > max
            || texture.height() > max
        {
            return Err(RenderError::OutputTooLarge { width, height });
        }
        let sizes = Sizes {
            output: [width as f32, height as f32],
            texture: [texture.width() as f32, texture.height() as f32],
        };
        let uniform = self.buffer(
            "sizes",
            bytemuck::bytes_of(&sizes),
            wgpu::BufferUsages::UNIFORM,
        );
        let bind_group = picture_bind_group(
            &self.device,
            &self.queue,
            &self.layout,
            &uniform,
            &self.sampler,
            texture,
        );
        self.offscreen(width, height, |pass| {
            pass.set_bind_group(0, &bind_group, &[]);
            record(pass);
        })
    }

    /// The device, for drawing with [`crate::MeshView`] offscreen.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue of [`GpuContext::device`].
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// Runs `record` in a render pass into a `width × height` RGBA8 (unorm) target
    /// cleared to transparent, and reads the target back, unpremultiplied.
    ///
    /// # Errors
    /// A size the device cannot hold, or a GPU failure.
    pub fn offscreen(
        &self,
        width: u32,
        height: u32,
        record: impl FnOnce(&mut wgpu::RenderPass<'_>),
    ) -> Result<RgbaImage, RenderError> {
        let max = self.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::OutputTooLarge { width, height });
        }
        let size = |w, h| wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        };
        let target = self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("target"),
            size: size(width, height),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let row_bytes = width * 4;
        let padded = row_bytes.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: u64::from(padded) * u64::from(height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        {
            let target_view = target.create_view(&Default::default());
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("warp"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            record(&mut pass);
        }
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &target,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(height),
                },
            },
            size(width, height),
        );
        self.queue.submit([encoder.finish()]);
        let slice = readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| RenderError::Gpu(e.to_string()))?;
        rx.recv()
            .map_err(|e| RenderError::Gpu(e.to_string()))?
            .map_err(|e| RenderError::Gpu(e.to_string()))?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| RenderError::Gpu(e.to_string()))?;
        let mut out = RgbaImage::new(width, height);
        for (y, row) in data
            .chunks(padded as usize)
            .take(height as usize)
            .enumerate()
        {
            for (x, p) in row[..row_bytes as usize].chunks_exact(4).enumerate() {
                out.put_pixel(
                    x as u32,
                    y as u32,
                    image::Rgba(unpremultiply([p[0], p[1], p[2], p[3]])),
                );
            }
        }
        Ok(out)
    }
}

/// A render pipeline drawing into an RGBA8 target, each (premultiplied) fragment
/// composited over what is there, vertex attributes `attributes` in one interleaved
/// buffer.
fn make_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layouts: &[Option<&wgpu::BindGroupLayout>],
    attributes: &[wgpu::VertexFormat],
) -> wgpu::RenderPipeline {
    let mut offset = 0;
    let attributes: Vec<wgpu::VertexAttribute> = attributes
        .iter()
        .enumerate()
        .map(|(i, &format)| {
            let a = wgpu::VertexAttribute {
                format,
                offset,
                shader_location: i as u32,
            };
            offset += format.size();
            a
        })
        .collect();
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("warp"),
        bind_group_layouts: layouts,
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("warp"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: offset,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &attributes,
            })],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: FORMAT,
                blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Uploads `image` premultiplied as an RGBA8 texture and binds it with `uniform` and
/// `sampler` (bindings 0, 1, 2 of both shaders' group 0). An empty image becomes one
/// transparent texel.
pub(crate) fn picture_bind_group(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    layout: &wgpu::BindGroupLayout,
    uniform: &wgpu::Buffer,
    sampler: &wgpu::Sampler,
    image: &RgbaImage,
) -> wgpu::BindGroup {
    let blank;
    let image = if image.width() == 0 || image.height() == 0 {
        blank = RgbaImage::new(1, 1);
        &blank
    } else {
        image
    };
    let texture = device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some("picture"),
            size: wgpu::Extent3d {
                width: image.width(),
                height: image.height(),
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &premultiply(image),
    );
    let view = texture.create_view(&Default::default());
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("picture"),
        layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&view),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::Sampler(sampler),
            },
        ],
    })
}

/// The bind group of [`SKIN_WGSL`]: row offsets, weight entries, node transforms.
pub(crate) fn skin_bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    buffers: [&wgpu::Buffer; 3],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding: binding as u32,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("skin"),
        layout,
        entries: &entries,
    })
}

/// `v`, or one `filler` element if `v` is empty.
fn nonempty<T: Copy>(mut v: Vec<T>, filler: T) -> Vec<T> {
    if v.is_empty() {
        v.push(filler);
    }
    v
}

/// Keeps far-away positions finite for the rasteriser.
fn clamp(p: Vec2) -> [f32; 2] {
    p.clamp(Vec2::splat(-1e6), Vec2::splat(1e6)).to_array()
}

fn unpremultiply([r, g, b, a]: [u8; 4]) -> [u8; 4] {
    if a == 0 {
        return [0, 0, 0, 0];
    }
    let u = |c: u8| ((u32::from(c) * 255 + u32::from(a) / 2) / u32::from(a)).min(255) as u8;
    [u(r), u(g), u(b), a]
}
