//! Headless rendering to images, with no window or display: the path for CI, frame dumps
//! and installations monitored from files.

use crate::camera::Camera;
use crate::frame::Frame;
use crate::render::{self, Gpu, RenderOptions, SceneRenderer, Targets};
use crate::ViewerError;
use image::RgbaImage;
use std::path::Path;

/// The colour format of offscreen pictures: 8-bit sRGB, as written to PNG.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// Description of the adapter a renderer runs on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterDescription {
    /// Adapter name, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`.
    pub name: String,
    /// Backend, e.g. `Gl` or `Vulkan`.
    pub backend: String,
    /// Device type, e.g. `Cpu`.
    pub device_type: String,
    /// Samples per pixel used (4 with multisampling, else 1).
    pub samples: u32,
}

impl std::fmt::Display for AdapterDescription {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} ({}, {}, {}× MSAA)",
            self.name, self.backend, self.device_type, self.samples
        )
    }
}

/// Renders frames into images of a fixed size without any window.
pub struct OffscreenRenderer {
    gpu: Gpu,
    scene: SceneRenderer,
    targets: Targets,
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    readback: wgpu::Buffer,
    padded_row: u32,
}

impl OffscreenRenderer {
    /// A renderer of `width`×`height` pictures on the first adapter wgpu finds (any
    /// backend; `WGPU_BACKEND=gl|vulkan` narrows it).
    pub fn new(width: u32, height: u32) -> Result<OffscreenRenderer, ViewerError> {
        Self::with_backends(width, height, wgpu::Backends::all())
    }

    /// A renderer restricted to `backends`.
    pub fn with_backends(
        width: u32,
        height: u32,
        backends: wgpu::Backends,
    ) -> Result<OffscreenRenderer, ViewerError> {
        if width == 0 || height == 0 || width > 8192 || height > 8192 {
            return Err(ViewerError::Invalid(format!(
                "picture size {width}x{height}: each side must be 1 to 8192 pixels"
            )));
        }
        let instance = render::instance(backends, None);
        let gpu = pollster::block_on(Gpu::new(&instance, backends, None))?;
        let max = gpu.device.limits().max_texture_dimension_2d;
        if width > max || height > max {
            return Err(ViewerError::Invalid(format!(
                "picture size {width}x{height}: this adapter allows at most {max} pixels a side"
            )));
        }
        let samples = gpu.sample_count(FORMAT);
        let scene = SceneRenderer::new(&gpu.device, FORMAT, samples);
        let targets = Targets::new(&gpu.device, width, height, FORMAT, samples);
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("offscreen colour"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let padded_row = (width * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: padded_row as u64 * height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        gpu.take_error()?;
        Ok(OffscreenRenderer {
            gpu,
            scene,
            targets,
            texture,
            view,
            readback,
            padded_row,
        })
    }

    /// Picture width in pixels.
    pub fn width(&self) -> u32 {
        self.targets.width
    }

    /// Picture height in pixels.
    pub fn height(&self) -> u32 {
        self.targets.height
    }

    /// The adapter in use.
    pub fn adapter(&self) -> AdapterDescription {
        let info = self.gpu.adapter.get_info();
        AdapterDescription {
            name: info.name,
            backend: format!("{:?}", info.backend),
            device_type: format!("{:?}", info.device_type),
            samples: self.scene.samples,
        }
    }

    /// Turns 4× multisampling on (when the adapter supports it, the default) or off
    /// (faster on CPU adapters, jagged edges).
    pub fn set_multisampling(&mut self, on: bool) {
        let samples = if on { self.gpu.sample_count(FORMAT) } else { 1 };
        if samples == self.scene.samples {
            return;
        }
        let options = self.scene.options;
        self.scene = SceneRenderer::new(&self.gpu.device, FORMAT, samples);
        self.scene.options = options;
        self.targets = Targets::new(
            &self.gpu.device,
            self.targets.width,
            self.targets.height,
            FORMAT,
            samples,
        );
    }

    /// The drawing options.
    pub fn options(&self) -> RenderOptions {
        self.scene.options
    }

    /// Changes the drawing options for the following pictures.
    pub fn set_options(&mut self, options: RenderOptions) {
        self.scene.options = options;
    }

    /// Renders `frame` seen by `camera` and reads the picture back.
    pub fn render(&mut self, frame: &Frame, camera: &Camera) -> Result<RgbaImage, ViewerError> {
        let (w, h) = (self.targets.width, self.targets.height);
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("offscreen"),
            });
        self.scene.encode(
            &self.gpu,
            &mut encoder,
            &self.view,
            &self.targets,
            frame,
            camera,
        );
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        self.gpu.queue.submit([encoder.finish()]);
        let slice = self.readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.gpu
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| ViewerError::Gpu(format!("waiting for the frame: {e}")))?;
        self.gpu.take_error()?;
        rx.recv()
            .map_err(|_| ViewerError::Gpu("the frame read-back was dropped".into()))?
            .map_err(|e| ViewerError::Gpu(format!("mapping the frame: {e}")))?;
        let mut pixels = Vec::with_capacity((w * h * 4) as usize);
        {
            let data = slice
                .get_mapped_range()
                .map_err(|e| ViewerError::Gpu(format!("reading the frame: {e}")))?;
            for row in data.chunks(self.padded_row as usize).take(h as usize) {
                pixels.extend_from_slice(&row[..(w * 4) as usize]);
            }
        }
        self.readback.unmap();
        RgbaImage::from_raw(w, h, pixels)
            .ok_or_else(|| ViewerError::Gpu("read-back size mismatch".into()))
    }

    /// Renders `frame` and writes it to `path` as PNG.
    pub fn save_png(
        &mut self,
        frame: &Frame,
        camera: &Camera,
        path: impl AsRef<Path>,
    ) -> Result<(), ViewerError> {
        let image = self.render(frame, camera)?;
        save_png(&image, path)
    }
}

/// Writes `image` to `path` as PNG, creating the parent directory if needed.
pub fn save_png(image: &RgbaImage, path: impl AsRef<Path>) -> Result<(), ViewerError> {
    let path = path.as_ref();
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| ViewerError::Io {
            path: dir.display().to_string(),
            source: e,
        })?;
    }
    image
        .save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| ViewerError::Image {
            path: path.display().to_string(),
            reason: e.to_string(),
        })
}
