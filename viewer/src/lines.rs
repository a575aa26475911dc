//! Lines in the scene: world-space segments drawn a few pixels wide, depth-tested
//! against the floor and the bodies (a body in front hides a line behind it), for debug
//! overlays such as the navigation view.
//!
//! Each segment is one instance: the vertex shader (`vs_line` in `shader.wgsl`) projects
//! both ends and widens the segment into a screen-space quad, its width in pixels of a
//! 720-pixel-high picture, scaled with the picture. wgpu's own line primitive is one
//! pixel wide on every backend, too thin to read in a large picture.

use crate::color::linear_rgba;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// One segment to draw: from `a` to `b` (world, m), `width` pixels (of a 720-pixel-high
/// picture), in a linear colour.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Segment {
    /// xyz: one end; w: the width in pixels.
    a: [f32; 4],
    /// xyz: the other end.
    b: [f32; 4],
    color: [f32; 4],
}

impl Segment {
    /// A segment from `a` to `b`, `width` pixels wide, in the sRGB colour `color`.
    pub fn new(a: Vec3, b: Vec3, width: f32, color: [f32; 3]) -> Segment {
        Segment {
            a: a.extend(width).to_array(),
            b: b.extend(0.0).to_array(),
            color: linear_rgba(color),
        }
    }
}

/// The line pipeline and its instance buffer, grown as needed.
pub(crate) struct LineRenderer {
    pipeline: wgpu::RenderPipeline,
    buffer: wgpu::Buffer,
    capacity: usize,
    /// This frame's segments.
    pub segments: Vec<Segment>,
}

impl LineRenderer {
    /// The pipeline for the colour and depth `formats` and `samples`, sharing the
    /// scene's globals `layout` (`shader` holds `vs_line` and `fs_line`).
    pub fn new(
        device: &wgpu::Device,
        shader: &wgpu::ShaderModule,
        layout: &wgpu::PipelineLayout,
        (format, depth_format): (wgpu::TextureFormat, wgpu::TextureFormat),
        samples: u32,
    ) -> LineRenderer {
        let attributes = wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4, 2 => Float32x4];
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("lines"),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module: shader,
                entry_point: Some("vs_line"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<Segment>() as u64,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &attributes,
                })],
            },
            primitive: wgpu::PrimitiveState::default(),
            // Tested against the floor and bodies, but not written: lines that cross do
            // not cut one another.
            depth_stencil: Some(wgpu::DepthStencilState {
                format: depth_format,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::LessEqual),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: samples,
                mask: !0,
                alpha_to_coverage_enabled: false,
            },
            fragment: Some(wgpu::FragmentState {
                module: shader,
                entry_point: Some("fs_line"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let capacity = 256;
        LineRenderer {
            pipeline,
            buffer: Self::buffer(device, capacity),
            capacity,
            segments: Vec::new(),
        }
    }

    fn buffer(device: &wgpu::Device, capacity: usize) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("line segments"),
            size: (capacity * std::mem::size_of::<Segment>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Uploads this frame's segments.
    pub fn upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) {
        if self.segments.len() > self.capacity {
            self.capacity = self.segments.len().next_power_of_two();
            self.buffer = Self::buffer(device, self.capacity);
        }
        if !self.segments.is_empty() {
            queue.write_buffer(&self.buffer, 0, bytemuck::cast_slice(&self.segments));
        }
    }

    /// Draws the uploaded segments (the globals must be bound at group 0).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        if self.segments.is_empty() {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_vertex_buffer(0, self.buffer.slice(..));
        pass.draw(0..6, 0..self.segments.len() as u32);
    }
}
