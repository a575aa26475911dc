//! The drawing core shared by the offscreen renderer and the window: adapter and device
//! set-up with clear errors, pipelines, the mesh cache and per-frame instance building.

use crate::camera::Camera;
use crate::color::linear_rgba;
use crate::frame::{ActorFrame, Frame, HandState, IK_TARGET, SENSOR_IDLE, SENSOR_TOUCHING, SKIN};
use crate::lines::LineRenderer;
use crate::mesh::{self, MeshKey, Vertex};
use crate::skinned::{self, SkinBlock, SkinCache, SkinVertex, BLOCK_STRIDE};
use crate::text;
use crate::ViewerError;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Quat, Vec3};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use wgpu::util::DeviceExt;

/// How actors are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BodyStyle {
    /// The generated skin (`troupe_body::Skin`), deformed on the GPU: a smooth body with
    /// five-fingered hands and a face. A skeleton that cannot be skinned is drawn as
    /// solids.
    #[default]
    Skin,
    /// The body solids (thesis 3.1) plus thin finger bones.
    Solids,
    /// A stick figure: a thin cylinder per bone and a small sphere per joint.
    Bones,
}

/// What to draw besides the actors and objects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Solids or bones.
    pub style: BodyStyle,
    /// Draw the floor grid.
    pub grid: bool,
    /// Draw overlays: sphere sensors, IK targets and hand grasp-state tints.
    pub overlays: bool,
    /// Draw each actor's name and labels above its head (built-in 5×7 pixel font).
    pub labels: bool,
    /// Background colour (sRGB).
    pub background: [f32; 3],
}

impl BodyStyle {
    /// Parses a `--look` value: `skin`, `solids` or `bones`.
    pub fn parse(s: &str) -> Option<BodyStyle> {
        match s {
            "skin" => Some(BodyStyle::Skin),
            "solids" => Some(BodyStyle::Solids),
            "bones" => Some(BodyStyle::Bones),
            _ => None,
        }
    }

    /// The next look, for the window's `b` key: skin → solids → bones → skin.
    pub fn next(self) -> BodyStyle {
        match self {
            BodyStyle::Skin => BodyStyle::Solids,
            BodyStyle::Solids => BodyStyle::Bones,
            BodyStyle::Bones => BodyStyle::Skin,
        }
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            style: BodyStyle::Skin,
            grid: true,
            overlays: true,
            labels: true,
            background: BACKGROUND,
        }
    }
}

/// Default background colour (sRGB).
pub const BACKGROUND: [f32; 3] = [0.80, 0.84, 0.88];
/// The panel behind a frame's notice (linear RGBA).
const NOTICE_PANEL: [f32; 4] = [0.45, 0.02, 0.02, 0.85];
const FLOOR: [f32; 3] = [0.90, 0.91, 0.92];
const GRID: [f32; 3] = [0.62, 0.65, 0.70];

/// Shirt colours (sRGB) given to actors in turn.
const SHIRTS: [[f32; 3]; 6] = [
    [0.18, 0.52, 0.58],
    [0.78, 0.28, 0.24],
    [0.86, 0.64, 0.18],
    [0.52, 0.36, 0.68],
    [0.92, 0.48, 0.20],
    [0.40, 0.48, 0.58],
];
const TROUSERS: [[f32; 3]; 3] = [[0.22, 0.24, 0.32], [0.30, 0.26, 0.22], [0.34, 0.34, 0.36]];
const SHOES: [f32; 3] = [0.14, 0.12, 0.11];
const EYE_WHITE: [f32; 3] = [0.94, 0.93, 0.90];
const PUPIL: [f32; 3] = [0.10, 0.07, 0.05];

/// The wgpu objects that outlive any one target.
pub(crate) struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: wgpu::Adapter,
    errors: Arc<Mutex<Vec<String>>>,
}

/// The install hint for a machine without a usable adapter.
pub(crate) const INSTALL_HINT: &str = "troupe renders on any GPU or on the CPU with Mesa: \
     install Mesa's EGL/GL driver (Debian/Ubuntu: `apt-get install libegl1 libgl1-mesa-dri`, \
     llvmpipe) or its Vulkan driver (`apt-get install mesa-vulkan-drivers libvulkan1`, \
     lavapipe); WGPU_BACKEND=gl or WGPU_BACKEND=vulkan picks one. \
     The simulation itself runs without the viewer.";

impl Gpu {
    /// Requests an adapter (compatible with `surface` if given) and a device.
    pub async fn new(
        instance: &wgpu::Instance,
        backends: wgpu::Backends,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Gpu, ViewerError> {
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: surface,
                apply_limit_buckets: false,
            })
            .await
            .map_err(|e| ViewerError::NoAdapter {
                backends: format!("{backends:?}"),
                reason: e.to_string(),
            })?;
        let info = adapter.get_info();
        tracing::info!(
            "viewer adapter: {} ({:?}, {:?})",
            info.name,
            info.backend,
            info.device_type
        );
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("troupe viewer"),
                required_features: wgpu::Features::empty(),
                required_limits: wgpu::Limits::downlevel_webgl2_defaults()
                    .using_resolution(adapter.limits()),
                experimental_features: wgpu::ExperimentalFeatures::disabled(),
                memory_hints: wgpu::MemoryHints::Performance,
                trace: wgpu::Trace::Off,
            })
            .await
            .map_err(|e| ViewerError::Device {
                adapter: format!("{} ({:?})", info.name, info.backend),
                reason: e.to_string(),
            })?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            tracing::error!("wgpu: {e}");
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        Ok(Gpu {
            device,
            queue,
            adapter,
            errors,
        })
    }

    /// The first GPU error raised since the last call, if any.
    pub fn take_error(&self) -> Result<(), ViewerError> {
        let mut v = self.errors.lock().unwrap_or_else(|p| p.into_inner());
        let first = v.drain(..).next();
        match first {
            Some(e) => Err(ViewerError::Gpu(e)),
            None => Ok(()),
        }
    }

    /// The largest sample count (4 or 1) usable for `format` with a depth buffer.
    pub fn sample_count(&self, format: wgpu::TextureFormat) -> u32 {
        let color = self.adapter.get_texture_format_features(format).flags;
        let depth = self.adapter.get_texture_format_features(DEPTH_FORMAT).flags;
        if color.sample_count_supported(4)
            && color.contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE)
            && depth.sample_count_supported(4)
        {
            4
        } else {
            1
        }
    }
}

/// Creates an instance for `backends`, taking `WGPU_BACKEND` and friends into account.
pub(crate) fn instance(
    backends: wgpu::Backends,
    display: Option<Box<dyn wgpu::wgt::WgpuHasDisplayHandle>>,
) -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backends;
    if let Some(d) = display {
        desc = desc.with_display_handle(d);
    }
    wgpu::Instance::new(desc.with_env())
}

pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The multisampled colour and depth attachments of one size.
pub(crate) struct Targets {
    pub width: u32,
    pub height: u32,
    msaa: Option<wgpu::TextureView>,
    depth: wgpu::TextureView,
}

impl Targets {
    pub fn new(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
        samples: u32,
    ) -> Targets {
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let make = |label, format, samples| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size,
                    mip_level_count: 1,
                    sample_count: samples,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                    view_formats: &[],
                })
                .create_view(&wgpu::TextureViewDescriptor::default())
        };
        Targets {
            width,
            height,
            msaa: (samples > 1).then(|| make("msaa colour", format, samples)),
            depth: make("depth", DEPTH_FORMAT, samples),
        }
    }
}

/// One mesh instance: a rigid placement, a non-uniform scale and a linear colour.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Instance {
    rotation: [f32; 4],
    translation: [f32; 4],
    scale: [f32; 4],
    color: [f32; 4],
}

impl Instance {
    fn new(rotation: Quat, translation: Vec3, scale: Vec3, color: [f32; 4]) -> Instance {
        Instance {
            rotation: rotation.normalize().to_array(),
            translation: translation.extend(1.0).to_array(),
            scale: scale.max(Vec3::splat(1e-5)).extend(1.0).to_array(),
            color,
        }
    }
}

/// A screen rectangle in pixels (x, y, width, height) and its linear colour with alpha.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct RectInstance {
    rect: [f32; 4],
    color: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    light_dir: [f32; 4],
    background: [f32; 4],
    floor_color: [f32; 4],
    grid_color: [f32; 4],
    viewport: [f32; 4],
}

struct GpuMesh {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    count: u32,
}

/// Pipelines, meshes and buffers for one colour format and sample count.
pub(crate) struct SceneRenderer {
    pub options: RenderOptions,
    mesh_pipeline: wgpu::RenderPipeline,
    floor_pipeline: wgpu::RenderPipeline,
    rect_pipeline: wgpu::RenderPipeline,
    rects: Vec<RectInstance>,
    rect_buffer: wgpu::Buffer,
    rect_capacity: usize,
    globals: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    meshes: HashMap<MeshKey, GpuMesh>,
    instances: wgpu::Buffer,
    capacity: usize,
    scratch: Vec<(MeshKey, Instance)>,
    batches: Vec<(MeshKey, std::ops::Range<u32>)>,
    pub samples: u32,
    skin_pipeline: wgpu::RenderPipeline,
    skin_by_vertex_pipeline: wgpu::RenderPipeline,
    /// Users' characters: by vertex, both faces drawn.
    character_pipeline: wgpu::RenderPipeline,
    skin_layout: wgpu::BindGroupLayout,
    skin_blocks: wgpu::Buffer,
    skin_bind_group: wgpu::BindGroup,
    skin_capacity: usize,
    skins: SkinCache,
    /// This frame's skinned actors: skeleton key, the level of detail to draw.
    skin_draws: Vec<(
        skinned::SkinKey,
        std::sync::Arc<troupe_body::Skeleton>,
        skinned::Detail,
    )>,
    skin_data: Vec<u8>,
    /// Debug lines (the navigation view).
    lines: LineRenderer,
}

impl SceneRenderer {
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat, samples: u32) -> SceneRenderer {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("troupe viewer shader"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("globals"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("globals"),
            size: std::mem::size_of::<Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewer"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let depth = |write: bool| {
            Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(write),
                depth_compare: Some(wgpu::CompareFunction::LessEqual),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            })
        };
        let multisample = wgpu::MultisampleState {
            count: samples,
            mask: !0,
            alpha_to_coverage_enabled: false,
        };
        let targets = [Some(wgpu::ColorTargetState {
            format,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let vertex_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
        let instance_attrs = wgpu::vertex_attr_array![
            2 => Float32x4, 3 => Float32x4, 4 => Float32x4, 5 => Float32x4
        ];
        let mesh_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("meshes"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs_mesh"),
                compilation_options: Default::default(),
                buffers: &[
                    Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<Vertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &vertex_attrs,
                    }),
                    Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<Instance>() as u64,
                        step_mode: wgpu::VertexStepMode::Instance,
                        attributes: &instance_attrs,
                    }),
                ],
            },
            // Every mesh is a closed convex shape wound counter-clockwise seen from outside
            // (`mesh::build`): its back faces are hidden.
            primitive: wgpu::PrimitiveState {
                cull_mode: Some(wgpu::Face::Back),
                ..Default::default()
            },
            depth_stencil: depth(true),
            multisample,
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs_mesh"),
                compilation_options: Default::default(),
                targets: &targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        let floor_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("floor"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs_floor"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: depth(true),
            multisample,
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs_floor"),
                compilation_options: Default::default(),
                targets: &targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        let rect_attrs = wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4];
        let rect_targets = [Some(wgpu::ColorTargetState {
            format,
            blend: Some(wgpu::BlendState::ALPHA_BLENDING),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let rect_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("labels"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs_rect"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<RectInstance>() as u64,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &rect_attrs,
                })],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample,
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs_rect"),
                compilation_options: Default::default(),
                targets: &rect_targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        let skin_layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("actor skin block"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    // The matrices skin the vertices; the colours are picked per pixel.
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(
                            std::mem::size_of::<SkinBlock>() as u64
                        ),
                    },
                    count: None,
                }],
            });
        let skin_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("skin"),
            bind_group_layouts: &[Some(&layout), Some(&skin_layout)],
            immediate_size: 0,
        });
        // The near generated skin picks its colours per pixel (`fs_skin`); its far level
        // of detail and users' characters by vertex, as the plain meshes (`vs_skin_by_vertex`).
        // The generated skin is closed (no edge without its twin, at any level) and
        // wound counter-clockwise seen from outside, so its back faces are hidden and
        // need not be drawn. (The few triangles turned over at rest lie inside small
        // folds, under their neighbours.) A user's character is drawn the same way, or
        // with both faces when its file's materials are double-sided (an open mesh, a
        // cloak's hem), as glTF asks.
        let skin_pipeline_with = |label, vertex, fragment, cull_mode| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&skin_pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some(vertex),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<SkinVertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &skinned::VERTEX_ATTRIBUTES,
                    })],
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode,
                    ..Default::default()
                },
                depth_stencil: depth(true),
                multisample,
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some(fragment),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &[("PUPIL_EDGE", troupe_body::skin::PUPIL_EDGE)],
                        ..Default::default()
                    },
                    targets: &targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let back = Some(wgpu::Face::Back);
        let skin_pipeline = skin_pipeline_with("skin", "vs_skin", "fs_skin", back);
        let skin_by_vertex_pipeline =
            skin_pipeline_with("skin by vertex", "vs_skin_by_vertex", "fs_mesh", back);
        let character_pipeline =
            skin_pipeline_with("character", "vs_skin_by_vertex", "fs_mesh", None);
        let lines = LineRenderer::new(
            device,
            &shader,
            &pipeline_layout,
            (format, DEPTH_FORMAT),
            samples,
        );
        let skin_capacity = 4;
        let (skin_blocks, skin_bind_group) = Self::skin_buffer(device, &skin_layout, skin_capacity);
        let capacity = 1024;
        SceneRenderer {
            lines,
            skin_pipeline,
            skin_by_vertex_pipeline,
            character_pipeline,
            skin_layout,
            skin_blocks,
            skin_bind_group,
            skin_capacity,
            skins: SkinCache::default(),
            skin_draws: Vec::new(),
            skin_data: Vec::new(),
            rect_pipeline,
            rects: Vec::new(),
            rect_buffer: Self::rect_buffer(device, capacity),
            rect_capacity: capacity,
            options: RenderOptions::default(),
            mesh_pipeline,
            floor_pipeline,
            globals,
            bind_group,
            meshes: HashMap::new(),
            instances: Self::instance_buffer(device, capacity),
            capacity,
            scratch: Vec::new(),
            batches: Vec::new(),
            samples,
        }
    }

    /// A uniform buffer for `capacity` actors' skin blocks and its bind group.
    fn skin_buffer(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        capacity: usize,
    ) -> (wgpu::Buffer, wgpu::BindGroup) {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("actor skin blocks"),
            size: BLOCK_STRIDE * capacity as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("actor skin blocks"),
            layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(std::mem::size_of::<SkinBlock>() as u64),
                }),
            }],
        });
        (buffer, bind_group)
    }

    fn rect_buffer(device: &wgpu::Device, capacity: usize) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("label rectangles"),
            size: (capacity * std::mem::size_of::<RectInstance>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Lays out every actor's name and labels above its head.
    fn build_labels(&mut self, frame: &Frame, view_proj: Mat4, width: u32, height: u32) {
        self.rects.clear();
        let scale = if height >= 400 { 2.0 } else { 1.0 };
        let line_height = text::CELL.1 as f32 * scale;
        let pad = 2.0 * scale;
        let panel = [0.02, 0.02, 0.03, 0.55];
        let ink = [1.0, 1.0, 1.0, 1.0];
        let mut glyphs = Vec::new();
        // The notice: a dark red panel in the top-left corner, one line per line.
        for (i, line) in frame.notice.iter().enumerate() {
            let (x, y) = (4.0 * scale, 4.0 * scale + i as f32 * (line_height + pad));
            let (w, h) = text::size(line, scale);
            self.rects.push(RectInstance {
                rect: [x - pad, y - pad, w + 2.0 * pad, h + 2.0 * pad],
                color: NOTICE_PANEL,
            });
            glyphs.clear();
            text::layout(line, x, y, scale, &mut glyphs);
            self.rects
                .extend(glyphs.iter().map(|&rect| RectInstance { rect, color: ink }));
        }
        if !self.options.labels {
            return;
        }
        for actor in &frame.actors {
            let Some(anchor) = actor.label_anchor() else {
                continue;
            };
            let c = view_proj * anchor.extend(1.0);
            if c.w <= 1e-4 {
                continue;
            }
            let (sx, sy) = (
                (c.x / c.w * 0.5 + 0.5) * width as f32,
                (0.5 - c.y / c.w * 0.5) * height as f32,
            );
            let lines: Vec<&str> = std::iter::once(actor.name.as_str())
                .chain(actor.labels.iter().map(String::as_str))
                .collect();
            // The last line sits just above the anchor; earlier lines stack upwards.
            let mut y = sy - lines.len() as f32 * line_height;
            for line in lines {
                let (w, h) = text::size(line, scale);
                let x = (sx - w * 0.5).round();
                let yy = y.round();
                self.rects.push(RectInstance {
                    rect: [x - pad, yy - pad, w + 2.0 * pad, h + 2.0 * pad],
                    color: panel,
                });
                glyphs.clear();
                text::layout(line, x, yy, scale, &mut glyphs);
                self.rects
                    .extend(glyphs.iter().map(|&rect| RectInstance { rect, color: ink }));
                y += line_height;
            }
        }
    }

    fn instance_buffer(device: &wgpu::Device, capacity: usize) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("instances"),
            size: (capacity * std::mem::size_of::<Instance>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Records the drawing of `frame` seen by `camera` into `encoder`, onto `view` (the
    /// final single-sample texture) through the multisampled `targets`.
    pub fn encode(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::TextureView,
        targets: &Targets,
        frame: &Frame,
        camera: &Camera,
    ) {
        let aspect = targets.width as f32 / targets.height.max(1) as f32;
        let (eye, _) = camera.eye_target(frame, aspect);
        let view_proj: Mat4 = camera.view_projection(frame, aspect);
        let light = Vec3::new(0.45, 0.85, 0.55).normalize();
        let bg = linear_rgba(self.options.background);
        let g = Globals {
            view_proj: view_proj.to_cols_array_2d(),
            eye: eye.extend(1.0).to_array(),
            light_dir: light.extend(0.0).to_array(),
            background: bg,
            floor_color: linear_rgba(FLOOR),
            grid_color: linear_rgba(GRID),
            viewport: [targets.width as f32, targets.height as f32, 0.0, 0.0],
        };
        gpu.queue
            .write_buffer(&self.globals, 0, bytemuck::bytes_of(&g));
        // Screen pixels covered by one metre at one metre from the eye.
        let pixels_per_metre =
            targets.height as f32 / (2.0 * (camera.fov_y_degrees.to_radians() * 0.5).tan());
        self.build_instances(gpu, frame, eye, pixels_per_metre);
        self.upload(gpu);
        self.upload_skins(gpu);
        self.build_labels(frame, view_proj, targets.width, targets.height);
        self.lines.segments.clear();
        if let Some(nav) = frame.nav.as_ref().filter(|_| self.options.overlays) {
            nav.segments(&mut self.lines.segments);
        }
        self.lines.upload(&gpu.device, &gpu.queue);
        if self.rects.len() > self.rect_capacity {
            self.rect_capacity = self.rects.len().next_power_of_two();
            self.rect_buffer = Self::rect_buffer(&gpu.device, self.rect_capacity);
        }
        if !self.rects.is_empty() {
            gpu.queue
                .write_buffer(&self.rect_buffer, 0, bytemuck::cast_slice(&self.rects));
        }

        let (attachment, resolve) = match &targets.msaa {
            Some(msaa) => (msaa, Some(view)),
            None => (view, None),
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: attachment,
                depth_slice: None,
                resolve_target: resolve,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: bg[0] as f64,
                        g: bg[1] as f64,
                        b: bg[2] as f64,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &self.bind_group, &[]);
        if self.options.grid {
            pass.set_pipeline(&self.floor_pipeline);
            pass.draw(0..6, 0..1);
        }
        pass.set_pipeline(&self.mesh_pipeline);
        pass.set_vertex_buffer(1, self.instances.slice(..));
        for (key, range) in &self.batches {
            let mesh = &self.meshes[key];
            pass.set_vertex_buffer(0, mesh.vertices.slice(..));
            pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..mesh.count, 0, range.clone());
        }
        if !self.skin_draws.is_empty() {
            for (i, (key, skeleton, detail)) in self.skin_draws.iter().enumerate() {
                let Some((skin, _)) = self.skins.get_key(&gpu.device, key, skeleton) else {
                    continue;
                };
                let level = skin.level(*detail);
                // Colours per pixel only where an edge between regions spans pixels.
                let pipeline = match (&skin.source, detail) {
                    (skinned::SkinSource::Generated(_), skinned::Detail::Near) => {
                        &self.skin_pipeline
                    }
                    (skinned::SkinSource::Generated(_), _) => &self.skin_by_vertex_pipeline,
                    // A character's back faces are culled unless its file asks
                    // for both faces (glTF's `doubleSided`).
                    (skinned::SkinSource::Character(d), _) if d.double_sided => {
                        &self.character_pipeline
                    }
                    (skinned::SkinSource::Character(_), _) => &self.skin_by_vertex_pipeline,
                };
                pass.set_pipeline(pipeline);
                pass.set_bind_group(
                    1,
                    &self.skin_bind_group,
                    &[(i as u64 * BLOCK_STRIDE) as u32],
                );
                pass.set_vertex_buffer(0, level.vertices.slice(..));
                pass.set_index_buffer(level.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..level.count, 0, 0..1);
            }
        }
        self.lines.draw(&mut pass);
        if !self.rects.is_empty() {
            pass.set_pipeline(&self.rect_pipeline);
            pass.set_vertex_buffer(0, self.rect_buffer.slice(..));
            pass.draw(0..6, 0..self.rects.len() as u32);
        }
    }

    fn upload(&mut self, gpu: &Gpu) {
        self.scratch.sort_by_key(|(k, _)| *k);
        self.batches.clear();
        let mut data = Vec::with_capacity(self.scratch.len());
        for (i, (key, inst)) in self.scratch.iter().enumerate() {
            data.push(*inst);
            match self.batches.last_mut() {
                Some((k, r)) if k == key => r.end = i as u32 + 1,
                _ => self.batches.push((*key, i as u32..i as u32 + 1)),
            }
            self.meshes.entry(*key).or_insert_with(|| {
                let (v, idx) = mesh::build(*key);
                GpuMesh {
                    vertices: gpu
                        .device
                        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                            label: Some("mesh vertices"),
                            contents: bytemuck::cast_slice(&v),
                            usage: wgpu::BufferUsages::VERTEX,
                        }),
                    indices: gpu
                        .device
                        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                            label: Some("mesh indices"),
                            contents: bytemuck::cast_slice(&idx),
                            usage: wgpu::BufferUsages::INDEX,
                        }),
                    count: idx.len() as u32,
                }
            });
        }
        if data.len() > self.capacity {
            self.capacity = data.len().next_power_of_two();
            self.instances = Self::instance_buffer(&gpu.device, self.capacity);
        }
        if !data.is_empty() {
            gpu.queue
                .write_buffer(&self.instances, 0, bytemuck::cast_slice(&data));
        }
    }

    /// Writes the skin blocks gathered by `build_instances` into the uniform buffer.
    fn upload_skins(&mut self, gpu: &Gpu) {
        if self.skin_draws.len() > self.skin_capacity {
            self.skin_capacity = self.skin_draws.len().next_power_of_two();
            (self.skin_blocks, self.skin_bind_group) =
                Self::skin_buffer(&gpu.device, &self.skin_layout, self.skin_capacity);
        }
        if !self.skin_data.is_empty() {
            gpu.queue
                .write_buffer(&self.skin_blocks, 0, &self.skin_data);
        }
    }

    /// Fills the instance list and the skinned actors' blocks; fingers of actors too far
    /// away to show them (under about 6 pixels long) are left out to spare CPU adapters,
    /// and skins under about 360 pixels tall use their coarse mesh.
    fn build_instances(&mut self, gpu: &Gpu, frame: &Frame, eye: Vec3, pixels_per_metre: f32) {
        self.scratch.clear();
        self.skin_draws.clear();
        self.skin_data.clear();
        let overlays = self.options.overlays;
        for (i, actor) in frame.actors.iter().enumerate() {
            let colors = ActorColors::new(i, actor, overlays);
            let root = actor
                .globals
                .first()
                .map_or(Vec3::ZERO, |t| t.translation.as_vec3());
            let distance = (root - eye).length().max(0.05);
            let style = match self.options.style {
                BodyStyle::Skin => match self.skins.get_key(
                    &gpu.device,
                    &skinned::SkinKey::of(actor),
                    &actor.skeleton,
                ) {
                    Some((skin, scale)) => {
                        let block = skinned::block(&skin.source, actor, colors.slots(), scale);
                        self.skin_data.extend_from_slice(bytemuck::bytes_of(&block));
                        self.skin_data.resize(
                            self.skin_draws.len().saturating_add(1) * BLOCK_STRIDE as usize,
                            0,
                        );
                        let detail = skinned::Detail::for_height(1.8 * pixels_per_metre / distance);
                        self.skin_draws.push((
                            skinned::SkinKey::of(actor),
                            actor.skeleton.clone(),
                            detail,
                        ));
                        continue;
                    }
                    None => BodyStyle::Solids,
                },
                other => other,
            };
            match style {
                BodyStyle::Skin => unreachable!("skins are drawn above"),
                BodyStyle::Solids => {
                    self.solids(actor, &colors);
                    if 0.08 * pixels_per_metre / distance >= 6.0 {
                        self.bones(actor, &colors, true);
                    }
                }
                BodyStyle::Bones => self.bones(actor, &colors, false),
            }
            for f in crate::face::features(actor, SKIN) {
                let color = linear_rgba(f.color);
                let instance = Instance::new(f.rotation, f.center, f.radii, color);
                self.scratch.push((MeshKey::SphereLow, instance));
            }
        }
        for o in &frame.objects {
            let (key, scale) = mesh::shape_mesh(&o.shape);
            self.scratch.push((
                key,
                Instance::new(o.rotation, o.position, scale, linear_rgba(o.color)),
            ));
        }
        if overlays {
            for s in &frame.sensors {
                let c = if s.touching {
                    SENSOR_TOUCHING
                } else {
                    SENSOR_IDLE
                };
                self.scratch.push((
                    MeshKey::Sphere,
                    Instance::new(
                        Quat::IDENTITY,
                        s.position,
                        Vec3::splat(s.radius),
                        linear_rgba(c),
                    ),
                ));
            }
            for &t in &frame.ik_targets {
                self.scratch.push((
                    MeshKey::Sphere,
                    Instance::new(
                        Quat::IDENTITY,
                        t,
                        Vec3::splat(0.025),
                        linear_rgba(IK_TARGET),
                    ),
                ));
            }
        }
    }

    fn solids(&mut self, actor: &ActorFrame, colors: &ActorColors) {
        for (joint, solid) in actor.skeleton.solids() {
            let Some(g) = actor.globals.get(*joint) else {
                continue;
            };
            let rotation = (g.rotation * solid.orientation).as_quat();
            let center = g.transform_point(solid.center).as_vec3();
            let (key, scale) = mesh::shape_mesh(&solid.shape);
            let color = colors.solid(&solid.name);
            self.scratch
                .push((key, Instance::new(rotation, center, scale, color)));
        }
    }

    /// Draws bones as cylinders and joints as spheres; with `hands_only`, only the bones
    /// inside the hands (fingers, which have no solids), without joint spheres.
    fn bones(&mut self, actor: &ActorFrame, colors: &ActorColors, hands_only: bool) {
        let sk = &actor.skeleton;
        let mut segment = |a: Vec3, b: Vec3, radius: f32, color: [f32; 4]| {
            let d = b - a;
            let len = d.length();
            if len < 1e-4 {
                return;
            }
            let rot = Quat::from_rotation_arc(Vec3::Y, d / len);
            self.scratch.push((
                MeshKey::CylinderLow,
                Instance::new(
                    rot,
                    (a + b) * 0.5,
                    Vec3::new(radius, len * 0.5, radius),
                    color,
                ),
            ));
            // Joint balls; fingers next to the body solids do without (they are a few
            // pixels wide and would triple the triangle count of an actor).
            if !hands_only {
                self.scratch.push((
                    MeshKey::SphereLow,
                    Instance::new(Quat::IDENTITY, b, Vec3::splat(radius * 1.25), color),
                ));
            }
        };
        let pos = |j: usize| actor.globals[j].translation.as_vec3();
        for (j, joint) in sk.joints().iter().enumerate() {
            let Some(p) = joint.parent else { continue };
            // A bone belongs to a hand when it starts at the wrist or further out.
            let hand = colors.hand_of[p];
            if hands_only && hand.is_none() {
                continue;
            }
            let (radius, color) = match hand {
                Some(h) => (0.0075, colors.hands[h]),
                None => (0.02, colors.shirt),
            };
            if j < actor.globals.len() && p < actor.globals.len() {
                segment(pos(p), pos(j), radius, color);
            }
        }
        for (j, off) in sk.end_sites() {
            let Some(g) = actor.globals.get(*j) else {
                continue;
            };
            let (radius, color) = match colors.hand_of[*j] {
                Some(h) => (0.0075, colors.hands[h]),
                None if hands_only => continue,
                None => (0.02, colors.shirt),
            };
            segment(
                g.translation.as_vec3(),
                g.transform_point(*off).as_vec3(),
                radius,
                color,
            );
        }
    }
}

/// The colours of one actor's parts.
struct ActorColors {
    shirt: [f32; 4],
    trousers: [f32; 4],
    skin: [f32; 4],
    shoes: [f32; 4],
    hands: [[f32; 4]; 2],
    /// For each joint: `Some(0)` inside the left hand (below the wrist), `Some(1)` right.
    hand_of: Vec<Option<usize>>,
}

impl ActorColors {
    fn new(index: usize, actor: &ActorFrame, overlays: bool) -> ActorColors {
        let hand = |h: HandState| linear_rgba(if overlays { h.color() } else { SKIN });
        let sk = &actor.skeleton;
        let wrists = [sk.joint("l_wrist").ok(), sk.joint("r_wrist").ok()];
        let mut hand_of = vec![None; sk.joints().len()];
        for (j, joint) in sk.joints().iter().enumerate() {
            hand_of[j] = match wrists.iter().position(|w| *w == Some(j)) {
                Some(side) => Some(side),
                None => joint.parent.and_then(|p| hand_of[p]),
            };
        }
        ActorColors {
            shirt: linear_rgba(SHIRTS[index % SHIRTS.len()]),
            trousers: linear_rgba(TROUSERS[index % TROUSERS.len()]),
            skin: linear_rgba(SKIN),
            shoes: linear_rgba(SHOES),
            hands: [hand(actor.hands[0]), hand(actor.hands[1])],
            hand_of,
        }
    }

    /// The colour slots of the skin look, in `troupe_body::skin::Region` order then
    /// the left and right hands.
    fn slots(&self) -> [[f32; 4]; 8] {
        [
            self.skin,
            self.shirt,
            self.trousers,
            self.shoes,
            linear_rgba(EYE_WHITE),
            linear_rgba(PUPIL),
            self.hands[0],
            self.hands[1],
        ]
    }

    fn solid(&self, name: &str) -> [f32; 4] {
        let part = name.trim_start_matches("l_").trim_start_matches("r_");
        match part {
            "hand" if name.starts_with("l_") => self.hands[0],
            "hand" => self.hands[1],
            "head_neck" | "head" => self.skin,
            "down_torso" | "thigh" | "leg" => self.trousers,
            "foot" => self.shoes,
            _ => self.shirt,
        }
    }
}
