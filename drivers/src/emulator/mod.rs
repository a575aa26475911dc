//! Emulators that speak the Flock of Birds and CyberGlove protocols on a pseudo-terminal,
//! so drivers, probes and performer actors run without hardware.
//!
//! The emulators answer the same commands the drivers send (see `shared/reference/
//! devices.md`) and encode records exactly as the documented formats say, from a motion
//! source: a built-in synthetic motion, a BVH file, or a `.rec` recording.

use crate::driver::Reading;
use crate::fob::{self, OutputFormat, PositionRange, RecordLayout, ReportRate};
use crate::glove::{self, CMD_QUERY, CMD_STOP};
use crate::record::Recording;
use glam::{DMat3, DQuat, DVec3, EulerRot};
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A pseudo-terminal: the emulator owns the master side; the slave path is what a driver opens.
pub struct Pty {
    master: OwnedFd,
    /// Kept open so the master never reads EIO while no driver has the slave open.
    _slave: OwnedFd,
    path: String,
}

impl Pty {
    /// Opens a pty pair in raw mode (no echo, no line editing: a serial line).
    pub fn open() -> Result<Pty, String> {
        let mut master: libc::c_int = -1;
        let mut slave: libc::c_int = -1;
        let mut name = [0 as libc::c_char; 128];
        // SAFETY: the out-pointers are valid; termios and winsize may be null.
        let rc = unsafe {
            libc::openpty(
                &mut master,
                &mut slave,
                name.as_mut_ptr(),
                std::ptr::null(),
                std::ptr::null(),
            )
        };
        if rc != 0 {
            return Err(format!("openpty: {}", std::io::Error::last_os_error()));
        }
        // SAFETY: openpty returned two fresh descriptors that we now own.
        let (master, slave) =
            unsafe { (OwnedFd::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) };
        // SAFETY: `name` was NUL-terminated by openpty.
        let path = unsafe { std::ffi::CStr::from_ptr(name.as_ptr()) }
            .to_string_lossy()
            .into_owned();
        // SAFETY: valid fd and a zeroed termios that tcgetattr fills.
        unsafe {
            let mut t: libc::termios = std::mem::zeroed();
            if libc::tcgetattr(slave.as_raw_fd(), &mut t) == 0 {
                libc::cfmakeraw(&mut t);
                libc::tcsetattr(slave.as_raw_fd(), libc::TCSANOW, &t);
            }
        }
        Ok(Pty {
            master,
            _slave: slave,
            path,
        })
    }

    /// The slave device path (`/dev/pts/N`).
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Reads what is available within `timeout` (empty when nothing came).
    fn read_timeout(&self, buf: &mut [u8], timeout: Duration) -> std::io::Result<usize> {
        let mut pfd = libc::pollfd {
            fd: self.master.as_raw_fd(),
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd.
        let n = unsafe { libc::poll(&mut pfd, 1, timeout.as_millis() as libc::c_int) };
        if n <= 0 || pfd.revents & libc::POLLIN == 0 {
            return Ok(0);
        }
        // SAFETY: buf is valid for buf.len() bytes.
        let k = unsafe { libc::read(self.master.as_raw_fd(), buf.as_mut_ptr().cast(), buf.len()) };
        if k < 0 {
            Err(std::io::Error::last_os_error())
        } else {
            Ok(k as usize)
        }
    }

    /// Writes all bytes (the pty buffer is large; a full buffer waits briefly).
    fn write_all(&self, mut bytes: &[u8]) -> std::io::Result<()> {
        while !bytes.is_empty() {
            // SAFETY: bytes is valid for its length.
            let k =
                unsafe { libc::write(self.master.as_raw_fd(), bytes.as_ptr().cast(), bytes.len()) };
            if k < 0 {
                let e = std::io::Error::last_os_error();
                if e.kind() == std::io::ErrorKind::WouldBlock
                    || e.kind() == std::io::ErrorKind::Interrupted
                {
                    std::thread::sleep(Duration::from_millis(1));
                    continue;
                }
                return Err(e);
            }
            bytes = &bytes[k as usize..];
        }
        Ok(())
    }
}

/// Where an emulator's motion comes from.
pub enum Motion {
    /// Smooth built-in motion: each bird on its own slow orbit and rotation; glove fingers
    /// opening and closing in a wave.
    Synthetic,
    /// A BVH file: bird `i` follows joint `joints[i]`, positions scaled to metres.
    Bvh {
        /// The motion.
        bvh: Box<troupe_formats::bvh::Bvh>,
        /// Joint index per bird.
        joints: Vec<usize>,
        /// File units to metres.
        scale: f64,
    },
    /// Readings decoded from a recording, looped.
    Recorded {
        /// (time, reading) in recording order.
        readings: Vec<(f64, Reading)>,
    },
}

impl Motion {
    /// Loads a BVH or `.rec` file by extension; `joints` names the BVH joint of each bird
    /// (empty: the first joints of the hierarchy); `kind` picks the recorded stream
    /// (`fob` or `cyberglove`).
    pub fn from_file(
        path: &Path,
        kind: &str,
        joints: &[String],
        birds: usize,
        scale: f64,
    ) -> Result<Motion, String> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        match ext.as_str() {
            "bvh" => {
                let bvh = troupe_formats::bvh::read_bvh(path).map_err(|e| e.to_string())?;
                let idx: Vec<usize> = if joints.is_empty() {
                    (0..birds.min(bvh.joints().len())).collect()
                } else {
                    joints
                        .iter()
                        .map(|j| {
                            bvh.joint(j)
                                .ok_or_else(|| format!("{}: no joint '{j}'", path.display()))
                        })
                        .collect::<Result<_, _>>()?
                };
                if idx.len() < birds {
                    return Err(format!(
                        "{}: {} joints for {birds} birds",
                        path.display(),
                        idx.len()
                    ));
                }
                Ok(Motion::Bvh {
                    bvh: Box::new(bvh),
                    joints: idx,
                    scale,
                })
            }
            "rec" => {
                let rec = Recording::read(path)?;
                let s = rec.find(kind).ok_or_else(|| {
                    format!(
                        "{}: no single '{kind}' stream in the recording",
                        path.display()
                    )
                })?;
                let readings = rec.readings(s)?;
                if readings.is_empty() {
                    return Err(format!(
                        "{}: the '{kind}' stream has no complete record",
                        path.display()
                    ));
                }
                Ok(Motion::Recorded { readings })
            }
            _ => Err(format!("{}: expected a .bvh or .rec file", path.display())),
        }
    }

    /// Position (metres) and orientation of bird `i` (0-based) at time `t`.
    pub fn bird(&self, t: f64, i: usize) -> (DVec3, DQuat) {
        match self {
            Motion::Synthetic => synthetic_bird(t, i),
            Motion::Bvh { bvh, joints, scale } => {
                let frames = bvh.frame_count().max(1);
                let k = ((t / bvh.frame_time().max(1e-6)) as usize) % frames;
                let mut g = vec![troupe_body::transform::Transform::IDENTITY; bvh.joints().len()];
                bvh.global_transforms(k, &mut g);
                let tr = g[joints[i.min(joints.len() - 1)]];
                (tr.translation * *scale, tr.rotation)
            }
            Motion::Recorded { readings } => {
                let birds: Vec<&fob::BirdRecord> = readings
                    .iter()
                    .filter_map(|(_, r)| match r {
                        Reading::Bird(b)
                            if usize::from(b.address) == i + 1 || (b.address == 1 && i == 0) =>
                        {
                            Some(b)
                        }
                        _ => None,
                    })
                    .collect();
                let times: Vec<f64> = readings
                    .iter()
                    .filter(
                        |(_, r)| matches!(r, Reading::Bird(b) if usize::from(b.address) == i + 1),
                    )
                    .map(|(t, _)| *t)
                    .collect();
                match pick(&times, t) {
                    Some(k) => bird_pose(birds[k]),
                    None => synthetic_bird(0.0, i),
                }
            }
        }
    }

    /// Raw glove values (1…255) for `sensors` sensors at time `t`.
    pub fn glove(&self, t: f64, sensors: usize) -> Vec<u8> {
        match self {
            Motion::Recorded { readings } => {
                let gloves: Vec<(f64, &Vec<u8>)> = readings
                    .iter()
                    .filter_map(|(tt, r)| match r {
                        Reading::Glove(g) => Some((*tt, &g.raw)),
                        _ => None,
                    })
                    .collect();
                let times: Vec<f64> = gloves.iter().map(|g| g.0).collect();
                match pick(&times, t) {
                    Some(k) => {
                        let mut v = gloves[k].1.clone();
                        v.resize(sensors, 128);
                        v
                    }
                    None => synthetic_glove(t, sensors),
                }
            }
            _ => synthetic_glove(t, sensors),
        }
    }
}

/// Index of the latest time ≤ `t` modulo the duration (loops the recording).
fn pick(times: &[f64], t: f64) -> Option<usize> {
    let (first, last) = (*times.first()?, *times.last()?);
    let span = (last - first).max(1e-3);
    let tt = first + (t % (span + 0.01)).min(span);
    Some(times.partition_point(|&x| x <= tt).saturating_sub(1))
}

/// The pose a bird record describes (orientation from whichever field the format has).
/// An all-zero quaternion or matrix gives a non-finite rotation: callers check.
pub fn bird_pose(b: &fob::BirdRecord) -> (DVec3, DQuat) {
    let p = b.position.map(DVec3::from_array).unwrap_or(DVec3::ZERO);
    let q = if let Some([w, x, y, z]) = b.quaternion {
        DQuat::from_xyzw(x, y, z, w).normalize()
    } else if let Some(a) = b.angles {
        angles_to_quat(a)
    } else if let Some(m) = b.matrix {
        DQuat::from_mat3(&DMat3::from_cols_array(&m)).normalize()
    } else {
        DQuat::IDENTITY
    };
    (p, q)
}

/// Orientation from azimuth (about Z), elevation (about Y), roll (about X), in degrees,
/// applied in that order as the Flock defines its Euler angles.
pub fn angles_to_quat(a: [f64; 3]) -> DQuat {
    DQuat::from_euler(
        EulerRot::ZYX,
        a[0].to_radians(),
        a[1].to_radians(),
        a[2].to_radians(),
    )
}

/// Azimuth, elevation, roll (degrees) of an orientation.
pub fn quat_to_angles(q: DQuat) -> [f64; 3] {
    let (z, y, x) = q.to_euler(EulerRot::ZYX);
    [z.to_degrees(), y.to_degrees(), x.to_degrees()]
}

fn synthetic_bird(t: f64, i: usize) -> (DVec3, DQuat) {
    let f = i as f64;
    let p = DVec3::new(
        0.3 + 0.05 * f + 0.1 * (0.9 * t + f).sin(),
        0.2 * (0.7 * t + 0.5 * f).sin(),
        -0.1 + 0.08 * (1.1 * t + f).cos(),
    );
    let a = [
        40.0 * (0.5 * t + f).sin(),
        25.0 * (0.8 * t).sin(),
        15.0 * (0.3 * t + f).cos(),
    ];
    (p, angles_to_quat(a))
}

fn synthetic_glove(t: f64, sensors: usize) -> Vec<u8> {
    (0..sensors)
        .map(|k| {
            let phase = 0.25 * k as f64;
            (1.0 + 254.0 * (0.5 - 0.5 * (1.5 * t + phase).cos()))
                .round()
                .clamp(1.0, 255.0) as u8
        })
        .collect()
}

/// The words of one bird record in a format, from a pose.
pub fn pose_words(format: OutputFormat, range: PositionRange, p: DVec3, q: DQuat) -> Vec<i16> {
    let mut w = Vec::with_capacity(12);
    let pos = [p.x, p.y, p.z].map(|v| fob::position_word(v, range));
    let with_pos = matches!(
        format,
        OutputFormat::Position
            | OutputFormat::PositionAngles
            | OutputFormat::PositionMatrix
            | OutputFormat::PositionQuaternion
    );
    if with_pos {
        w.extend_from_slice(&pos);
    }
    match format {
        OutputFormat::Angles | OutputFormat::PositionAngles => {
            w.extend(quat_to_angles(q).map(fob::angle_word));
        }
        OutputFormat::Quaternion | OutputFormat::PositionQuaternion => {
            w.extend([q.w, q.x, q.y, q.z].map(fob::unit_word));
        }
        OutputFormat::Matrix | OutputFormat::PositionMatrix => {
            w.extend(DMat3::from_quat(q).to_cols_array().map(fob::unit_word));
        }
        OutputFormat::Position => {}
    }
    w
}

/// Emulator settings.
pub struct EmulatorOptions {
    /// Birds in the flock (FoB), ignored by the glove.
    pub birds: u8,
    /// Position range the emulated transmitter has.
    pub range: PositionRange,
    /// Glove sensors (18 or 22).
    pub sensors: usize,
    /// Measurement rate in Hz (FoB ~100 Hz; glove stream rate).
    pub rate_hz: f64,
    /// Motion source.
    pub motion: Motion,
}

impl EmulatorOptions {
    /// Six birds, 36-inch range, an 18-sensor glove, 100 Hz, synthetic motion.
    pub fn new() -> EmulatorOptions {
        EmulatorOptions {
            birds: 6,
            range: PositionRange::Inches36,
            sensors: 18,
            rate_hz: 100.0,
            motion: Motion::Synthetic,
        }
    }
}

impl Default for EmulatorOptions {
    fn default() -> Self {
        EmulatorOptions::new()
    }
}

/// A running emulator: its pty path; stops (closing the pty) when dropped.
pub struct Emulator {
    path: String,
    link: Option<PathBuf>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Emulator {
    /// The path a driver opens (the link when one was asked for, else the pty).
    pub fn path(&self) -> String {
        self.link
            .as_ref()
            .map(|l| l.display().to_string())
            .unwrap_or_else(|| self.path.clone())
    }

    /// The pty's own path.
    pub fn pty_path(&self) -> &str {
        &self.path
    }

    /// Stops the emulator and closes the pty (a connected driver sees the port vanish).
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        if let Some(l) = &self.link {
            remove_symlink(l);
        }
    }

    /// Waits until the emulator thread ends (it runs until stopped).
    pub fn join(mut self) {
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Emulator {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Which device to emulate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceKind {
    /// Flock of Birds.
    Fob,
    /// CyberGlove.
    CyberGlove,
}

/// Starts an emulator on a new pty; with `link`, a symbolic link at that path points to the
/// pty (replaced if it exists), so a driver can reopen the same path after a restart.
pub fn start(
    kind: DeviceKind,
    options: EmulatorOptions,
    link: Option<&Path>,
) -> Result<Emulator, String> {
    let pty = Pty::open()?;
    let path = pty.path().to_string();
    if let Some(l) = link {
        if std::fs::symlink_metadata(l).is_ok_and(|m| !m.file_type().is_symlink()) {
            return Err(format!(
                "--link {}: a file that is not a symbolic link is there; not replacing it",
                l.display()
            ));
        }
        remove_symlink(l);
        std::os::unix::fs::symlink(&path, l)
            .map_err(|e| format!("linking {} to {path}: {e}", l.display()))?;
    }
    let stop = Arc::new(AtomicBool::new(false));
    let s = stop.clone();
    let thread = std::thread::Builder::new()
        .name(format!("emulator {path}"))
        .spawn(move || match kind {
            DeviceKind::Fob => FobEmulator::new(options).run(&pty, &s),
            DeviceKind::CyberGlove => GloveEmulator::new(options).run(&pty, &s),
        })
        .map_err(|e| format!("starting the emulator thread: {e}"))?;
    Ok(Emulator {
        path,
        link: link.map(Path::to_path_buf),
        stop,
        thread: Some(thread),
    })
}

/// The Flock of Birds emulator's state.
pub struct FobEmulator {
    options: EmulatorOptions,
    format: OutputFormat,
    hemisphere: [u8; 2],
    rate: ReportRate,
    group: bool,
    streaming: bool,
    /// Pending command bytes not yet complete.
    pending: Vec<u8>,
    /// Expanded error code (EXAMINE VALUE 0x10).
    error: u8,
    start: Instant,
}

impl FobEmulator {
    /// A flock at power-up: POSITION/ANGLES, forward hemisphere, every cycle, not streaming.
    pub fn new(options: EmulatorOptions) -> FobEmulator {
        FobEmulator {
            options,
            format: OutputFormat::PositionAngles,
            hemisphere: [0, 0],
            rate: ReportRate::Every,
            group: false,
            streaming: false,
            pending: Vec::new(),
            error: 0,
            start: Instant::now(),
        }
    }

    fn layout(&self) -> RecordLayout {
        RecordLayout {
            format: self.format,
            button: false,
            group: self.group,
            range: self.options.range,
        }
    }

    /// One report: every bird's record in group mode, else bird 1's.
    pub fn report(&self, t: f64) -> Vec<u8> {
        let layout = self.layout();
        let birds = if self.group {
            self.options.birds.max(1)
        } else {
            1
        };
        let mut out = Vec::new();
        for i in 0..birds {
            let (p, q) = self.options.motion.bird(t, usize::from(i));
            let words = pose_words(self.format, self.options.range, p, q);
            out.extend(fob::encode_record(&layout, &words, 0, i + 1));
        }
        out
    }

    /// Consumes command bytes; returns the reply bytes. Incomplete commands wait for more.
    pub fn handle(&mut self, bytes: &[u8], t: f64) -> Vec<u8> {
        self.pending.extend_from_slice(bytes);
        let mut reply = Vec::new();
        loop {
            let p = &self.pending;
            let Some(&c) = p.first() else { break };
            // The RS232-TO-FBB prefix addresses the next command to one bird; the emulator
            // keeps one format for the whole flock, so the prefix is consumed with it.
            let (addr_len, cmd) = if (0xF1..=0xFE).contains(&c) {
                match p.get(1) {
                    Some(&c2) => (1, c2),
                    None => break,
                }
            } else {
                (0, c)
            };
            let extra = match cmd {
                fob::CMD_HEMISPHERE => 2,
                fob::CMD_EXAMINE => 1,
                fob::CMD_CHANGE => 2,
                _ => 0,
            };
            let need = addr_len + 1 + extra;
            if p.len() < need {
                break;
            }
            let args: Vec<u8> = p[addr_len + 1..need].to_vec();
            self.pending.drain(..need);
            match cmd {
                fob::CMD_POINT => {
                    self.streaming = false;
                    reply.extend(self.report(t));
                }
                fob::CMD_STREAM => self.streaming = true,
                fob::CMD_RUN => {}
                fob::CMD_SLEEP => self.streaming = false,
                fob::CMD_FBB_RESET => self.group = false,
                fob::CMD_HEMISPHERE => self.hemisphere = [args[0], args[1]],
                fob::CMD_EXAMINE => match args[0] {
                    fob::PARAM_FBB_STATUS => {
                        let s = fob::STATUS_ACCESSIBLE | fob::STATUS_RUNNING | fob::STATUS_RECEIVER;
                        reply.extend(std::iter::repeat_n(s, usize::from(self.options.birds)));
                    }
                    fob::PARAM_ERROR_CODE => reply.extend([self.error, 0]),
                    fob::PARAM_GROUP_MODE => reply.push(u8::from(self.group)),
                    _ => reply.extend([0, 0]),
                },
                fob::CMD_CHANGE => match args[0] {
                    fob::PARAM_GROUP_MODE => self.group = args[1] != 0,
                    fob::PARAM_AUTO_CONFIG => {
                        if args[1] != self.options.birds {
                            // The FBB has as many units as it has; a wrong count is an error.
                            self.error = 0x0E;
                        }
                    }
                    _ => self.error = 0x0D,
                },
                other => {
                    if let Some(f) = OutputFormat::from_command(other) {
                        self.format = f;
                    } else if let Some(r) = ReportRate::from_command(other) {
                        self.rate = r;
                    } else {
                        self.error = 0x0C;
                    }
                }
            }
        }
        reply
    }

    /// Serves the pty until stopped.
    pub fn run(mut self, pty: &Pty, stop: &AtomicBool) {
        let mut buf = [0u8; 256];
        let mut next = Instant::now();
        while !stop.load(Ordering::Acquire) {
            let n = match pty.read_timeout(&mut buf, Duration::from_millis(2)) {
                Ok(n) => n,
                Err(_) => {
                    std::thread::sleep(Duration::from_millis(5));
                    0
                }
            };
            let t = self.start.elapsed().as_secs_f64();
            if n > 0 {
                let reply = self.handle(&buf[..n], t);
                if !reply.is_empty() && pty.write_all(&reply).is_err() {
                    continue;
                }
            }
            if self.streaming && Instant::now() >= next {
                let period = f64::from(self.rate.divisor()) / self.options.rate_hz.max(1.0);
                next += Duration::from_secs_f64(period);
                if next < Instant::now() {
                    next = Instant::now();
                }
                let _ = pty.write_all(&self.report(t));
            }
        }
    }
}

/// The CyberGlove emulator's state.
pub struct GloveEmulator {
    options: EmulatorOptions,
    status_byte: bool,
    streaming: bool,
    pending: Vec<u8>,
    start: Instant,
}

impl GloveEmulator {
    /// A glove at power-up: not streaming, no status byte.
    pub fn new(options: EmulatorOptions) -> GloveEmulator {
        GloveEmulator {
            options,
            status_byte: false,
            streaming: false,
            pending: Vec::new(),
            start: Instant::now(),
        }
    }

    /// One record answering `letter`.
    pub fn record(&self, letter: u8, t: f64) -> Vec<u8> {
        let mut v = vec![letter];
        v.extend(self.options.motion.glove(t, self.options.sensors));
        if self.status_byte {
            // Status: initialized and glove plugged in (bits 0 and 1).
            v.push(0x03);
        }
        v.push(0);
        v
    }

    /// Consumes command bytes; returns the reply bytes.
    pub fn handle(&mut self, bytes: &[u8], t: f64) -> Vec<u8> {
        self.pending.extend_from_slice(bytes);
        let mut reply = Vec::new();
        while let Some(&c) = self.pending.first() {
            match c {
                glove::CMD_POLL => {
                    self.pending.remove(0);
                    reply.extend(self.record(b'G', t));
                }
                glove::CMD_STREAM => {
                    self.pending.remove(0);
                    self.streaming = true;
                }
                CMD_STOP => {
                    self.pending.remove(0);
                    self.streaming = false;
                }
                CMD_QUERY => {
                    let Some(&q) = self.pending.get(1) else { break };
                    self.pending.drain(..2);
                    let n = self.options.sensors as u8;
                    let payload: Vec<u8> = match q {
                        b'G' => vec![0x03],
                        b'S' | b'N' => vec![n],
                        b'M' => {
                            let mask: u32 = (1u32 << n) - 1;
                            vec![mask as u8, (mask >> 8) as u8, (mask >> 16) as u8]
                        }
                        b'R' => vec![1],
                        b'B' => vec![1],
                        b'T' => vec![0, 10],
                        b'V' => b"troupe-emulator 1".to_vec(),
                        _ => {
                            reply.extend(b"e?");
                            continue;
                        }
                    };
                    reply.extend([b'?', q]);
                    reply.extend(payload);
                    reply.push(0);
                }
                b'a'..=b'z' => {
                    // ASCII command, CR-terminated.
                    let Some(end) = self.pending.iter().position(|&b| b == b'\r') else {
                        break;
                    };
                    let line: Vec<u8> = self.pending.drain(..=end).collect();
                    let text = String::from_utf8_lossy(&line[..line.len() - 1]).to_string();
                    let words: Vec<&str> = text.split_whitespace().collect();
                    match words.as_slice() {
                        ["u", v] => self.status_byte = *v == "1",
                        _ => reply.extend(b"e?"),
                    }
                }
                _ => {
                    self.pending.remove(0);
                    reply.extend(b"e?");
                }
            }
        }
        reply
    }

    /// Serves the pty until stopped.
    pub fn run(mut self, pty: &Pty, stop: &AtomicBool) {
        let mut buf = [0u8; 256];
        let mut next = Instant::now();
        while !stop.load(Ordering::Acquire) {
            let n = pty
                .read_timeout(&mut buf, Duration::from_millis(2))
                .unwrap_or(0);
            let t = self.start.elapsed().as_secs_f64();
            if n > 0 {
                let reply = self.handle(&buf[..n], t);
                if !reply.is_empty() {
                    let _ = pty.write_all(&reply);
                }
            }
            if self.streaming && Instant::now() >= next {
                next += Duration::from_secs_f64(1.0 / self.options.rate_hz.max(1.0));
                if next < Instant::now() {
                    next = Instant::now();
                }
                let _ = pty.write_all(&self.record(b'S', t));
            }
        }
    }
}

/// Removes `path` if it is a symbolic link (the emulator's `--link`), and nothing else.
fn remove_symlink(path: &std::path::Path) {
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
        let _ = std::fs::remove_file(path);
    }
}
