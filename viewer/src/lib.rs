//! troupe's viewer: draws a scene with wgpu, headless into PNG pictures or live in a
//! window.
//!
//! - [`Frame`] is an owned snapshot of a [`Scene`] plus overlays (hand grasp states,
//!   sphere sensors, IK targets, action labels). The simulation builds frames; renderers
//!   only read them, so the simulation never depends on the viewer.
//! - [`Camera`] frames all actors (default), follows one or stays fixed; it parses from
//!   `fit`, `follow:NAME`, `fixed:EX,EY,EZ:TX,TY,TZ`.
//! - [`OffscreenRenderer`] renders frames to [`RgbaImage`]s with no display (Mesa's
//!   llvmpipe through EGL/GL, lavapipe through Vulkan, or any GPU).
//! - [`FrameWriter`] and [`render_scene_png`] are the one-call helpers for the CLI.
//! - [`run_window`] opens a winit window with an orbit camera and playback controls; the
//!   caller's simulation runs on its own thread and hands frames over latest-wins.
//!
//! Actor names and labels are drawn above the heads with a built-in 5×7 pixel font
//! (printable ASCII); the window also shows the followed actor's labels in its title bar.

#![warn(missing_docs)]

mod camera;
mod face;
mod frame;
mod mesh;
mod offscreen;
mod render;
mod skinned;
mod text;
mod window;

pub use camera::{Camera, Focus};
pub use frame::{
    ActorFrame, Frame, Hand, HandState, ObjectFrame, Sensor, IK_TARGET, OBJECT, SENSOR_IDLE,
    SENSOR_TOUCHING, SKIN,
};
pub use image::RgbaImage;
pub use offscreen::{save_png, AdapterDescription, OffscreenRenderer};
pub use render::{BodyStyle, RenderOptions, BACKGROUND};
pub use wgpu::Backends;
pub use window::{run_window, FrameSlot, PlaybackControl, WindowOptions};

use std::path::{Path, PathBuf};
use troupe_scene::Scene;

/// Everything that can go wrong in the viewer. None of it affects the simulation.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    /// No graphics adapter could be found.
    #[error(
        "no graphics adapter available (wgpu backends tried: {backends}; {reason}). {hint}",
        hint = render::INSTALL_HINT
    )]
    NoAdapter {
        /// The backends that were searched.
        backends: String,
        /// wgpu's reason.
        reason: String,
    },
    /// An adapter was found but refused to open a device.
    #[error("the graphics adapter {adapter} could not open a device: {reason}. {hint}", hint = render::INSTALL_HINT)]
    Device {
        /// Adapter name and backend.
        adapter: String,
        /// wgpu's reason.
        reason: String,
    },
    /// No display to open a window on.
    #[error(
        "cannot open a window: {reason}. Set DISPLAY (X11) or WAYLAND_DISPLAY, run under \
         `xvfb-run` (Debian: `apt-get install xvfb`), or render headless to PNG frames instead"
    )]
    NoDisplay {
        /// What the windowing system said.
        reason: String,
    },
    /// A GPU error while rendering.
    #[error("rendering failed: {0}")]
    Gpu(String),
    /// A bad argument (size, camera spec, …).
    #[error("{0}")]
    Invalid(String),
    /// A file system error.
    #[error("{path}: {source}")]
    Io {
        /// The path involved.
        path: String,
        /// The error.
        #[source]
        source: std::io::Error,
    },
    /// A picture could not be encoded or written.
    #[error("cannot write {path}: {reason}")]
    Image {
        /// The picture's path.
        path: String,
        /// The encoder's reason.
        reason: String,
    },
}

/// Parses a picture size `WIDTHxHEIGHT`, e.g. `1280x720`.
pub fn parse_size(s: &str) -> Result<(u32, u32), ViewerError> {
    let bad = || ViewerError::Invalid(format!("size `{s}`: expected WIDTHxHEIGHT, e.g. 1280x720"));
    let (w, h) = s.trim().split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        return Err(ViewerError::Invalid(format!(
            "size `{s}`: each side must be 1 to 8192 pixels"
        )));
    }
    Ok((w, h))
}

/// Renders `scene` once and writes it to `path` as PNG (for `troupe render`).
pub fn render_scene_png(
    scene: &Scene,
    camera: &Camera,
    (width, height): (u32, u32),
    path: impl AsRef<Path>,
) -> Result<(), ViewerError> {
    OffscreenRenderer::new(width, height)?.save_png(&Frame::from_scene(scene), camera, path)
}

/// Writes every N-th tick of a running scene as `DIR/frame_000000.png`, … (for
/// `troupe run --frames DIR`).
///
/// ```no_run
/// # use troupe_viewer::{Camera, FrameWriter};
/// # fn f(scene: &mut troupe_scene::Scene) -> Result<(), troupe_viewer::ViewerError> {
/// let mut frames = FrameWriter::new("frames", (1280, 720), Camera::fit(), 4)?;
/// for _ in 0..100 {
///     scene.step();
///     frames.tick(scene)?;
/// }
/// # Ok(()) }
/// ```
pub struct FrameWriter {
    renderer: OffscreenRenderer,
    dir: PathBuf,
    camera: Camera,
    every: u64,
    calls: u64,
    written: u64,
}

impl FrameWriter {
    /// Writes into `dir` (created if missing) every `every`-th call of [`FrameWriter::tick`].
    pub fn new(
        dir: impl Into<PathBuf>,
        (width, height): (u32, u32),
        camera: Camera,
        every: u64,
    ) -> Result<FrameWriter, ViewerError> {
        if every == 0 {
            return Err(ViewerError::Invalid("--every must be at least 1".into()));
        }
        let dir = dir.into();
        std::fs::create_dir_all(&dir).map_err(|e| ViewerError::Io {
            path: dir.display().to_string(),
            source: e,
        })?;
        Ok(FrameWriter {
            renderer: OffscreenRenderer::new(width, height)?,
            dir,
            camera,
            every,
            calls: 0,
            written: 0,
        })
    }

    /// The renderer (to change options or query the adapter).
    pub fn renderer_mut(&mut self) -> &mut OffscreenRenderer {
        &mut self.renderer
    }

    /// Counts one tick; on every N-th (the first included) renders `scene` and writes the
    /// next numbered PNG, returning its path.
    pub fn tick(&mut self, scene: &Scene) -> Result<Option<PathBuf>, ViewerError> {
        let due = self.calls.is_multiple_of(self.every);
        self.calls += 1;
        if !due {
            return Ok(None);
        }
        self.write(&Frame::from_scene(scene)).map(Some)
    }

    /// Renders `frame` (with any overlays the caller added) as the next numbered PNG.
    pub fn write(&mut self, frame: &Frame) -> Result<PathBuf, ViewerError> {
        let path = self.dir.join(format!("frame_{:06}.png", self.written));
        self.renderer.save_png(frame, &self.camera, &path)?;
        self.written += 1;
        Ok(path)
    }

    /// Pictures written so far.
    pub fn written(&self) -> u64 {
        self.written
    }
}

impl troupe_scene::Observer for FrameWriter {
    fn name(&self) -> String {
        format!("--frames {}", self.dir.display())
    }

    /// The first picture shows the scene before the first tick.
    fn start(&mut self, scene: &Scene) -> troupe_scene::Result<()> {
        self.tick(scene).map(drop).map_err(frame_error)
    }

    fn publish(
        &mut self,
        scene: &Scene,
        _events: &[troupe_scene::Event],
    ) -> troupe_scene::Result<()> {
        self.tick(scene).map(drop).map_err(frame_error)
    }

    fn finish(&mut self, _scene: &Scene) -> troupe_scene::Result<Option<String>> {
        Ok(Some(format!(
            "wrote {} frames to {} (rendered on {})",
            self.written,
            self.dir.display(),
            self.renderer.adapter()
        )))
    }
}

fn frame_error(e: ViewerError) -> troupe_scene::Error {
    troupe_scene::Error::Invalid(e.to_string())
}
