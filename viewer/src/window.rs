//! The live window: winit 0.30 event loop on the calling thread, the caller's simulation
//! on its own thread, frames handed over latest-wins so the simulation never waits for
//! the renderer.
//!
//! Controls: left drag orbits, right or middle drag pans, the wheel zooms; Space pauses,
//! `.` steps one tick while paused, `s` toggles slow motion (¼ speed), Tab follows the next
//! actor, `1`–`9` follow actor N, `0` or `f` frames all actors, `b` cycles skin/solids/bones,
//! `g` the grid, `o` the overlays, `l` the labels, Escape or `q` quits.

use crate::camera::{Camera, Focus};
use crate::frame::Frame;
use crate::render::{self, Gpu, RenderOptions, SceneRenderer, Targets};
use crate::ViewerError;
use glam::Vec3;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::{LogicalSize, PhysicalPosition};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

/// A one-frame mailbox: the newest published frame replaces any unread one.
#[derive(Clone, Debug, Default)]
pub struct FrameSlot(Arc<Mutex<Option<Frame>>>);

impl FrameSlot {
    /// An empty slot.
    pub fn new() -> FrameSlot {
        FrameSlot::default()
    }

    /// Publishes `frame`, dropping any frame not yet taken. Never blocks on the renderer
    /// for longer than a pointer swap.
    pub fn publish(&self, frame: Frame) {
        let mut slot = self.0.lock().unwrap_or_else(|p| p.into_inner());
        *slot = Some(frame);
    }

    /// Takes the newest frame, if one arrived since the last take.
    pub fn take(&self) -> Option<Frame> {
        self.0.lock().unwrap_or_else(|p| p.into_inner()).take()
    }
}

/// Playback state shared by the window (which changes it) and the simulation thread.
#[derive(Debug)]
pub struct PlaybackControl {
    paused: AtomicBool,
    steps: AtomicU64,
    speed_bits: AtomicU64,
    quit: AtomicBool,
}

impl Default for PlaybackControl {
    fn default() -> Self {
        PlaybackControl {
            paused: AtomicBool::new(false),
            steps: AtomicU64::new(0),
            speed_bits: AtomicU64::new(1.0f64.to_bits()),
            quit: AtomicBool::new(false),
        }
    }
}

impl PlaybackControl {
    /// Whether playback is paused.
    pub fn is_paused(&self) -> bool {
        self.paused.load(Ordering::Relaxed)
    }
    /// Pauses or resumes.
    pub fn set_paused(&self, paused: bool) {
        self.paused.store(paused, Ordering::Relaxed);
    }
    /// Asks for one more tick while paused.
    pub fn request_step(&self) {
        self.steps.fetch_add(1, Ordering::Relaxed);
    }
    /// Consumes one requested single step, if any.
    pub fn take_step(&self) -> bool {
        self.steps
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| n.checked_sub(1))
            .is_ok()
    }
    /// Playback speed (1 = real time).
    pub fn speed(&self) -> f64 {
        f64::from_bits(self.speed_bits.load(Ordering::Relaxed))
    }
    /// Sets the playback speed (clamped to 0.01 … 100).
    pub fn set_speed(&self, speed: f64) {
        let s = if speed.is_finite() {
            speed.clamp(0.01, 100.0)
        } else {
            1.0
        };
        self.speed_bits.store(s.to_bits(), Ordering::Relaxed);
    }
    /// Asks the simulation thread to stop.
    pub fn request_quit(&self) {
        self.quit.store(true, Ordering::Relaxed);
    }
    /// Whether the window has closed.
    pub fn quit_requested(&self) -> bool {
        self.quit.load(Ordering::Relaxed)
    }
}

/// How the window starts.
#[derive(Clone, Debug)]
pub struct WindowOptions {
    /// Window title prefix.
    pub title: String,
    /// Inner size in logical pixels.
    pub size: (u32, u32),
    /// Initial camera.
    pub camera: Camera,
    /// Initial drawing options.
    pub render: RenderOptions,
    /// Simulated seconds per call of the step closure (the scene's tick).
    pub tick_seconds: f64,
    /// Closes the window by itself after drawing this many frames (smoke tests, demos).
    pub close_after_frames: Option<u64>,
}

impl Default for WindowOptions {
    fn default() -> Self {
        WindowOptions {
            title: "troupe".into(),
            size: (1280, 720),
            camera: Camera::fit(),
            render: RenderOptions::default(),
            tick_seconds: 0.01,
            close_after_frames: None,
        }
    }
}

/// Opens a window and plays a simulation in it until the window closes.
///
/// `step` advances the simulation by one tick and returns the frame to show; it runs on
/// its own thread, paced to real time × the playback speed, and is never blocked by
/// drawing. Must be called from the main thread on platforms that require it (macOS).
/// Fails with [`ViewerError::NoDisplay`] when there is no display, before `step` is ever
/// called.
pub fn run_window<F>(options: WindowOptions, step: F) -> Result<(), ViewerError>
where
    F: FnMut() -> Frame + Send + 'static,
{
    let event_loop = new_event_loop()?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let slot = FrameSlot::new();
    let control = Arc::new(PlaybackControl::default());
    let sim = spawn_simulation(step, options.tick_seconds, slot.clone(), control.clone());
    let display = Box::new(event_loop.owned_display_handle());
    let mut app = App {
        instance: render::instance(wgpu::Backends::all(), Some(display)),
        camera: options.camera.clone(),
        render: options.render,
        options,
        slot,
        control: control.clone(),
        state: None,
        error: None,
        frame: Frame::default(),
        drag: None,
        cursor: PhysicalPosition::new(0.0, 0.0),
        drawn: 0,
        title: String::new(),
    };
    let run = event_loop.run_app(&mut app);
    control.request_quit();
    let joined = sim.join();
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    run.map_err(|e| ViewerError::NoDisplay {
        reason: e.to_string(),
    })?;
    if joined.is_err() {
        return Err(ViewerError::Invalid(
            "the simulation thread panicked".into(),
        ));
    }
    Ok(())
}

fn new_event_loop() -> Result<EventLoop<()>, ViewerError> {
    #[allow(unused_mut)]
    let mut builder = EventLoop::builder();
    #[cfg(target_os = "linux")]
    {
        // Tests and embedding programs may drive the window from another thread; on Linux
        // (X11, Wayland) that is safe.
        use winit::platform::wayland::EventLoopBuilderExtWayland;
        use winit::platform::x11::EventLoopBuilderExtX11;
        EventLoopBuilderExtX11::with_any_thread(&mut builder, true);
        EventLoopBuilderExtWayland::with_any_thread(&mut builder, true);
    }
    builder.build().map_err(|e| ViewerError::NoDisplay {
        reason: e.to_string(),
    })
}

fn spawn_simulation<F>(
    mut step: F,
    tick: f64,
    slot: FrameSlot,
    control: Arc<PlaybackControl>,
) -> std::thread::JoinHandle<()>
where
    F: FnMut() -> Frame + Send + 'static,
{
    let tick = if tick.is_finite() && tick > 0.0 {
        tick
    } else {
        0.01
    };
    std::thread::Builder::new()
        .name("troupe-sim".into())
        .spawn(move || {
            let mut next = Instant::now();
            while !control.quit_requested() {
                if control.is_paused() {
                    if control.take_step() {
                        slot.publish(step());
                    } else {
                        std::thread::sleep(Duration::from_millis(5));
                    }
                    next = Instant::now();
                    continue;
                }
                slot.publish(step());
                next += Duration::from_secs_f64(tick / control.speed());
                let now = Instant::now();
                if next > now {
                    std::thread::sleep(next - now);
                } else if now - next > Duration::from_millis(250) {
                    // Too slow to keep real time: drop the backlog rather than race.
                    next = now;
                }
            }
        })
        .expect("spawning the simulation thread")
}

struct WindowState {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    gpu: Gpu,
    config: wgpu::SurfaceConfiguration,
    scene: SceneRenderer,
    targets: Targets,
}

struct App {
    instance: wgpu::Instance,
    options: WindowOptions,
    camera: Camera,
    render: RenderOptions,
    slot: FrameSlot,
    control: Arc<PlaybackControl>,
    state: Option<WindowState>,
    error: Option<ViewerError>,
    frame: Frame,
    drag: Option<MouseButton>,
    cursor: PhysicalPosition<f64>,
    drawn: u64,
    title: String,
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, error: ViewerError) {
        self.error.get_or_insert(error);
        event_loop.exit();
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<WindowState, ViewerError> {
        let (w, h) = self.options.size;
        let window = event_loop
            .create_window(
                Window::default_attributes()
                    .with_title(self.options.title.clone())
                    .with_inner_size(LogicalSize::new(w, h)),
            )
            .map_err(|e| ViewerError::NoDisplay {
                reason: e.to_string(),
            })?;
        let window = Arc::new(window);
        let surface = self
            .instance
            .create_surface(window.clone())
            .map_err(|e| ViewerError::Gpu(format!("creating the window surface: {e}")))?;
        let gpu = pollster::block_on(Gpu::new(
            &self.instance,
            wgpu::Backends::all(),
            Some(&surface),
        ))?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&gpu.adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| ViewerError::Gpu("the adapter cannot present to this window".into()))?;
        let caps = surface.get_capabilities(&gpu.adapter);
        if let Some(srgb) = caps.formats.iter().find(|f| f.is_srgb()) {
            config.format = *srgb;
        }
        config.present_mode = wgpu::PresentMode::AutoVsync;
        surface.configure(&gpu.device, &config);
        let samples = gpu.sample_count(config.format);
        let mut scene = SceneRenderer::new(&gpu.device, config.format, samples);
        scene.options = self.render;
        let targets = Targets::new(
            &gpu.device,
            config.width,
            config.height,
            config.format,
            samples,
        );
        gpu.take_error()?;
        Ok(WindowState {
            window,
            surface,
            gpu,
            config,
            scene,
            targets,
        })
    }

    fn resize(&mut self, width: u32, height: u32) {
        let Some(s) = self.state.as_mut() else { return };
        if width == 0 || height == 0 {
            return;
        }
        s.config.width = width;
        s.config.height = height;
        s.surface.configure(&s.gpu.device, &s.config);
        s.targets = Targets::new(
            &s.gpu.device,
            width,
            height,
            s.config.format,
            s.scene.samples,
        );
    }

    fn aspect(&self) -> f32 {
        match &self.state {
            Some(s) => s.config.width as f32 / s.config.height.max(1) as f32,
            None => 16.0 / 9.0,
        }
    }

    fn draw(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(f) = self.slot.take() {
            self.frame = f;
        }
        self.update_title();
        let Some(s) = self.state.as_mut() else { return };
        s.scene.options = self.render;
        let texture = match s.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                let (w, h) = (s.config.width, s.config.height);
                self.resize(w, h);
                return;
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => return,
            wgpu::CurrentSurfaceTexture::Validation => {
                let e = s.gpu.take_error().err().unwrap_or_else(|| {
                    ViewerError::Gpu("acquiring the window's texture failed".into())
                });
                self.fail(event_loop, e);
                return;
            }
        };
        let view = texture
            .texture
            .create_view(&wgpu::TextureViewDescriptor::default());
        let mut encoder = s
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("window"),
            });
        s.scene.encode(
            &s.gpu,
            &mut encoder,
            &view,
            &s.targets,
            &self.frame,
            &self.camera,
        );
        s.gpu.queue.submit([encoder.finish()]);
        s.window.pre_present_notify();
        s.gpu.queue.present(texture);
        if let Err(e) = s.gpu.take_error() {
            self.fail(event_loop, e);
            return;
        }
        self.drawn += 1;
        if self
            .options
            .close_after_frames
            .is_some_and(|n| self.drawn >= n)
        {
            event_loop.exit();
        }
    }

    fn update_title(&mut self) {
        let mut t = format!("{} — t = {:.2} s", self.options.title, self.frame.time);
        if self.control.is_paused() {
            t.push_str(" — paused (. steps)");
        }
        let speed = self.control.speed();
        if speed != 1.0 {
            t.push_str(&format!(" — ×{speed}"));
        }
        let followed = match &self.camera.focus {
            Focus::Actor(name) => self.frame.actor(name),
            _ if self.frame.actors.len() == 1 => self.frame.actors.first(),
            _ => None,
        };
        if let Some(a) = followed {
            t.push_str(&format!(" — {}", a.name));
            if !a.labels.is_empty() {
                t.push_str(&format!(": {}", a.labels.join(", ")));
            }
        }
        if t != self.title {
            if let Some(s) = &self.state {
                s.window.set_title(&t);
            }
            self.title = t;
        }
    }

    fn follow(&mut self, index: usize) {
        if let Some(a) = self.frame.actors.get(index) {
            self.camera.focus = Focus::Actor(a.name.clone());
            self.camera.pan = Vec3::ZERO;
            self.camera.distance = None;
        }
    }

    fn key(&mut self, event_loop: &ActiveEventLoop, key: &Key) {
        match key {
            Key::Named(NamedKey::Space) => self.control.set_paused(!self.control.is_paused()),
            Key::Named(NamedKey::Escape) => event_loop.exit(),
            Key::Named(NamedKey::Tab) => {
                let n = self.frame.actors.len();
                if n > 0 {
                    let current = match &self.camera.focus {
                        Focus::Actor(name) => {
                            self.frame.actors.iter().position(|a| &a.name == name)
                        }
                        _ => None,
                    };
                    self.follow(current.map_or(0, |i| (i + 1) % n));
                }
            }
            Key::Character(c) => match c.as_str() {
                "." => {
                    self.control.set_paused(true);
                    self.control.request_step();
                }
                "s" | "S" => {
                    let slow = self.control.speed() < 1.0;
                    self.control.set_speed(if slow { 1.0 } else { 0.25 });
                }
                "0" | "f" | "F" => {
                    self.camera.focus = Focus::FitAll;
                    self.camera.pan = Vec3::ZERO;
                    self.camera.distance = None;
                }
                "b" | "B" => {
                    self.render.style = self.render.style.next();
                }
                "g" | "G" => self.render.grid = !self.render.grid,
                "o" | "O" => self.render.overlays = !self.render.overlays,
                "l" | "L" => self.render.labels = !self.render.labels,
                "q" | "Q" => event_loop.exit(),
                d => {
                    if let Some(n) = d.parse::<usize>().ok().filter(|n| (1..=9).contains(n)) {
                        self.follow(n - 1);
                    }
                }
            },
            _ => {}
        }
    }

    fn mouse_moved(&mut self, to: PhysicalPosition<f64>) {
        let (dx, dy) = ((to.x - self.cursor.x) as f32, (to.y - self.cursor.y) as f32);
        self.cursor = to;
        match self.drag {
            Some(MouseButton::Left) => {
                self.camera.yaw_degrees -= dx * 0.3;
                self.camera.pitch_degrees =
                    (self.camera.pitch_degrees + dy * 0.3).clamp(-89.0, 89.0);
            }
            Some(MouseButton::Right | MouseButton::Middle) => {
                let (eye, target) = self.camera.eye_target(&self.frame, self.aspect());
                let forward = (target - eye).normalize_or_zero();
                let right = forward.cross(Vec3::Y).normalize_or_zero();
                let up = right.cross(forward);
                let scale = (eye - target).length() * 0.0015;
                self.camera.pan += (-dx * right + dy * up) * scale;
            }
            _ => {}
        }
    }

    fn zoom(&mut self, steps: f32) {
        let (eye, target) = self.camera.eye_target(&self.frame, self.aspect());
        let d = (eye - target).length();
        self.camera.distance = Some((d * 0.9f32.powf(steps)).clamp(0.2, 500.0));
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(s) => {
                s.window.request_redraw();
                self.state = Some(s);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => self.resize(size.width, size.height),
            WindowEvent::RedrawRequested => self.draw(event_loop),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                self.key(event_loop, &event.logical_key)
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.drag = (state == ElementState::Pressed).then_some(button);
            }
            WindowEvent::CursorMoved { position, .. } => self.mouse_moved(position),
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.zoom(steps);
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(s) = &self.state {
            s.window.request_redraw();
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        self.control.request_quit();
    }
}
