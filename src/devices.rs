//! `troupe devices` (list, probe, calibrate-glove) and `troupe emulate`.

use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};
use troupe_drivers::cyberglove::{GloveCalibration, GloveConfig, GloveLayout, GloveProtocol};
use troupe_drivers::device::{self as driver, DriverOptions, Mode, Reading};
use troupe_drivers::emulator::{self, DeviceKind, EmulatorOptions, Motion};
use troupe_drivers::fob::{FobConfig, FobProtocol, Hemisphere, OutputFormat, PositionRange};
use troupe_drivers::record::Recording;

/// Options of `troupe devices`.
#[derive(Args)]
pub struct DevicesArgs {
    #[command(subcommand)]
    command: Option<DevicesCommand>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Subcommand)]
enum DevicesCommand {
    /// Configure a device and print decoded samples (the first thing to run after plugging in).
    Probe(ProbeArgs),
    /// Make a glove calibration from recordings of a flat hand and a fist.
    CalibrateGlove(CalibrateArgs),
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
enum ProbeKind {
    Fob,
    Cyberglove,
    Spacemouse,
    Vmc,
    Vrpn,
}

#[derive(Args)]
struct ProbeArgs {
    /// Which device.
    kind: ProbeKind,
    /// Serial port (FoB, CyberGlove) or hidraw path (SpaceMouse; default: the first found).
    #[arg(long)]
    port: Option<String>,
    /// VRPN device: `Tracker0@host[:port]` or `Tracker0@tcp://host:port`.
    #[arg(long)]
    device: Option<String>,
    /// VRPN: also read these button or analog devices of the same server (comma-separated).
    #[arg(long, value_delimiter = ',')]
    also: Vec<String>,
    /// VMC: the UDP address to listen on (a Performer's port for Assistants by default).
    #[arg(long, default_value = "0.0.0.0:39540")]
    listen: String,
    /// FoB output format: position, angles, matrix, quaternion, position-angles,
    /// position-matrix, position-quaternion.
    #[arg(long, default_value = "position-angles")]
    format: String,
    /// FoB birds (more than one: group mode).
    #[arg(long, default_value_t = 1)]
    birds: u8,
    /// FoB position range in inches: 36, 72 or 144.
    #[arg(long, default_value = "36")]
    range: String,
    /// FoB hemisphere.
    #[arg(long, default_value = "forward")]
    hemisphere: String,
    /// Glove sensors: 18 or 22.
    #[arg(long, default_value_t = 18)]
    sensors: usize,
    /// Glove calibration (JSON) to print calibrated angles too.
    #[arg(long)]
    calibration: Option<PathBuf>,
    /// point (one record per request) or stream.
    #[arg(long, default_value = "stream")]
    mode: String,
    /// Baud rate.
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// Samples to print.
    #[arg(long, default_value_t = 10)]
    samples: usize,
    /// Give up after this many seconds without the samples.
    #[arg(long, default_value_t = 5.0)]
    timeout: f64,
    /// One JSON object per line.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct CalibrateArgs {
    /// Recording (.rec) of the flat hand.
    #[arg(long)]
    flat: PathBuf,
    /// Recording (.rec) of the fist.
    #[arg(long)]
    fist: PathBuf,
    /// Hand: right or left.
    #[arg(long, default_value = "right")]
    hand: String,
    /// Where to write the calibration (JSON).
    #[arg(long)]
    out: PathBuf,
}

/// Options of `troupe emulate`.
#[derive(Args)]
pub struct EmulateArgs {
    /// Which device: fob, cyberglove (on a pseudo-terminal) or vmc (a VMC sender over UDP).
    kind: EmulateKind,
    /// Motion from a BVH file or a .rec recording (default: built-in synthetic motion).
    #[arg(long)]
    from: Option<PathBuf>,
    /// Birds in the flock.
    #[arg(long, default_value_t = 6)]
    birds: u8,
    /// BVH joints followed by birds 1, 2, … (comma-separated; default: the first joints).
    #[arg(long, value_delimiter = ',')]
    joints: Vec<String>,
    /// BVH units to metres.
    #[arg(long, default_value_t = 0.01)]
    scale: f64,
    /// Position range of the emulated transmitter, inches.
    #[arg(long, default_value = "36")]
    range: String,
    /// Glove sensors: 18 or 22.
    #[arg(long, default_value_t = 18)]
    sensors: usize,
    /// Measurement rate, Hz (default 100; VMC frames: 60).
    #[arg(long)]
    rate: Option<f64>,
    /// VMC: where to send the stream, HOST:PORT (a Marionette listens on 39539; a troupe
    /// performer on 39540).
    #[arg(long, default_value = "127.0.0.1:39540")]
    to: String,
    /// Also make a symbolic link at this path to the pty (stable across restarts).
    #[arg(long)]
    link: Option<PathBuf>,
    /// Stop after this many seconds (default: run until interrupted).
    #[arg(long)]
    seconds: Option<f64>,
}

#[derive(Clone, Copy, ValueEnum)]
enum EmulateKind {
    Fob,
    Cyberglove,
    Vmc,
}

fn mode(m: &str) -> Result<Mode> {
    match m {
        "stream" => Ok(Mode::Stream),
        "point" => Ok(Mode::Point),
        other => bail!("--mode must be point or stream, got '{other}'"),
    }
}

/// `troupe devices …`.
pub fn run(args: DevicesArgs) -> Result<ExitCode> {
    match args.command {
        None => list(args.json),
        Some(DevicesCommand::Probe(p)) => probe(p),
        Some(DevicesCommand::CalibrateGlove(c)) => calibrate(c),
    }
}

fn list(json: bool) -> Result<ExitCode> {
    let serial = troupe_drivers::device::serial_ports();
    let hid = troupe_drivers::spacemouse::hid_devices();
    if json {
        let v = serde_json::json!({
            "serial": serial.as_ref().ok(),
            "serial_error": serial.as_ref().err().map(|e| e.to_string()),
            "hid": hid.as_ref().ok(),
            "hid_error": hid.as_ref().err().map(|e| e.to_string()),
        });
        println!("{v}");
        return Ok(ExitCode::SUCCESS);
    }
    println!("serial ports:");
    match &serial {
        Ok(v) if v.is_empty() => println!("  (none)"),
        Ok(v) => v.iter().for_each(|p| println!("  {}  {}", p.path, p.kind)),
        Err(e) => println!("  unavailable: {e}"),
    }
    println!("HID devices:");
    match &hid {
        Ok(v) if v.is_empty() => println!("  (none)"),
        Ok(v) => v.iter().for_each(|d| {
            println!(
                "  {}  {:04x}:{:04x}  {}{}",
                d.path,
                d.vendor,
                d.product,
                d.name,
                d.spacemouse
                    .as_ref()
                    .map(|s| format!("  [SpaceMouse: {s}]"))
                    .unwrap_or_default()
            )
        }),
        Err(e) => println!("  unavailable: {e}"),
    }
    println!("(emulators: `troupe emulate fob` or `troupe emulate cyberglove` print a pty path to probe)");
    Ok(ExitCode::SUCCESS)
}

fn probe(a: ProbeArgs) -> Result<ExitCode> {
    let timeout = Duration::from_secs_f64(a.timeout.max(0.1));
    if a.kind == ProbeKind::Vmc {
        return probe_vmc(&a.listen, a.samples, timeout, a.json);
    }
    if a.kind == ProbeKind::Spacemouse {
        let json = a.json;
        let (name, n) = troupe_drivers::spacemouse::read_spacemouse(
            a.port.as_deref(),
            a.samples,
            timeout,
            |s| {
                if json {
                    println!("{}", serde_json::to_string(s).unwrap_or_default());
                } else {
                    println!(
                        "T {:6} {:6} {:6}  R {:6} {:6} {:6}  buttons {:#x}",
                        s.translation[0],
                        s.translation[1],
                        s.translation[2],
                        s.rotation[0],
                        s.rotation[1],
                        s.rotation[2],
                        s.buttons
                    );
                }
            },
        )
        .map_err(|e| anyhow!(e))?;
        eprintln!("{name}: {n} reports");
        return Ok(if n > 0 {
            ExitCode::SUCCESS
        } else {
            ExitCode::FAILURE
        });
    }
    if a.kind == ProbeKind::Vrpn {
        return probe_vrpn(&a, timeout);
    }
    let port = a.port.clone().ok_or_else(|| {
        anyhow!(
            "--port is required for {}",
            if a.kind == ProbeKind::Fob {
                "fob"
            } else {
                "cyberglove"
            }
        )
    })?;
    let mut o = DriverOptions::new("probe", &port);
    o.baud = a.baud;
    o.max_attempts = Some(3);
    let calibration = match &a.calibration {
        Some(p) => Some(GloveCalibration::load(p).map_err(|e| anyhow!(e))?),
        None => None,
    };
    let protocol: Box<dyn driver::Protocol> = match a.kind {
        ProbeKind::Fob => {
            if !(1..=14).contains(&a.birds) {
                bail!(
                    "--birds must be 1 to 14 (the FBB addresses of a flock), got {}",
                    a.birds
                );
            }
            let mut c = FobConfig::new(
                a.birds,
                OutputFormat::parse(&a.format).map_err(|e| anyhow!(e))?,
            );
            c.layout.range = PositionRange::parse(&a.range).map_err(|e| anyhow!(e))?;
            c.hemisphere = Hemisphere::parse(&a.hemisphere).map_err(|e| anyhow!(e))?;
            c.mode = mode(&a.mode)?;
            Box::new(FobProtocol::new(c))
        }
        _ => {
            if a.sensors != 18 && a.sensors != 22 {
                bail!("--sensors must be 18 or 22");
            }
            if let Some(c) = &calibration {
                if c.sensors.len() != a.sensors {
                    bail!(
                        "the calibration has {} sensors, --sensors is {}",
                        c.sensors.len(),
                        a.sensors
                    );
                }
            }
            Box::new(GloveProtocol::new(GloveConfig {
                layout: GloveLayout {
                    sensors: a.sensors,
                    status_byte: false,
                },
                mode: mode(&a.mode)?,
            }))
        }
    };
    let dev = driver::spawn(o, protocol, None);
    let start = Instant::now();
    let mut n = 0;
    while n < a.samples && start.elapsed() < timeout {
        if dev.health.state() == driver::HealthState::Failed {
            break;
        }
        match dev.samples.recv_timeout(Duration::from_millis(50)) {
            Ok(s) => {
                print_sample(&s, calibration.as_ref(), a.json);
                n += 1;
            }
            Err(_) => continue,
        }
    }
    let h = dev.health.report();
    dev.stop();
    eprintln!(
        "{}: {} samples, {} resyncs, {} dropped bytes{}",
        h.state.name(),
        h.samples,
        h.resyncs,
        h.dropped_bytes,
        h.last_error
            .as_ref()
            .map(|e| format!("; last error: {e}"))
            .unwrap_or_default()
    );
    if n < a.samples {
        bail!(
            "got {n} of {} samples from {port} within {:.1} s{}",
            a.samples,
            a.timeout,
            h.last_error.map(|e| format!(" ({e})")).unwrap_or_default()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// `troupe devices probe vrpn --device Tracker0@host`: connects (each attempt bounded by
/// half the timeout, so a server that never answers is reported within it) and prints
/// the decoded reports.
fn probe_vrpn(a: &ProbeArgs, timeout: Duration) -> Result<ExitCode> {
    use troupe_drivers::vrpn::{self, DeviceName, VrpnConfig};
    let device = a
        .device
        .clone()
        .ok_or_else(|| anyhow!("--device is required for vrpn (Tracker0@host[:port])"))?;
    let name = DeviceName::parse(&device).map_err(|e| anyhow!(e))?;
    let mut o = vrpn::driver_options("probe", &device);
    o.max_attempts = Some(3);
    let handshake = vrpn::HANDSHAKE_TIMEOUT.min(timeout / 2);
    let dev =
        vrpn::spawn(VrpnConfig::new(&name, &a.also), o, handshake, None).map_err(|e| anyhow!(e))?;
    let start = Instant::now();
    let mut n = 0;
    while n < a.samples && start.elapsed() < timeout {
        if dev.health.state() == driver::HealthState::Failed {
            break;
        }
        if let Ok(s) = dev.samples.recv_timeout(Duration::from_millis(50)) {
            print_sample(&s, None, a.json);
            n += 1;
        }
    }
    let h = dev.health.report();
    dev.stop();
    eprintln!(
        "{}: {} reports, {} unusable messages{}",
        h.state.name(),
        h.samples,
        h.resyncs,
        h.last_error
            .as_ref()
            .map(|e| format!("; last error: {e}"))
            .unwrap_or_default()
    );
    if n < a.samples {
        bail!(
            "got {n} of {} reports from {device} within {:.1} s{}",
            a.samples,
            a.timeout,
            h.last_error.map(|e| format!(" ({e})")).unwrap_or_default()
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn print_sample(s: &driver::Sample, cal: Option<&GloveCalibration>, json: bool) {
    if json {
        let mut v = serde_json::json!({ "seq": s.seq, "time": s.time, "reading": &s.reading });
        if let (Reading::Glove(g), Some(c)) = (&s.reading, cal) {
            v["angles_deg"] = serde_json::json!(c
                .angles(&g.raw)
                .iter()
                .map(|a| a.to_degrees())
                .collect::<Vec<_>>());
        }
        println!("{v}");
        return;
    }
    match &s.reading {
        Reading::Bird(b) => {
            let mut line = format!("{:8.3}s bird {:2}", s.time, b.address);
            if let Some(p) = b.position {
                line += &format!("  pos {:8.4} {:8.4} {:8.4} m", p[0], p[1], p[2]);
            }
            if let Some(a) = b.angles {
                line += &format!(
                    "  azim/elev/roll {:8.2} {:8.2} {:8.2} deg",
                    a[0], a[1], a[2]
                );
            }
            if let Some(q) = b.quaternion {
                line += &format!("  quat {:7.4} {:7.4} {:7.4} {:7.4}", q[0], q[1], q[2], q[3]);
            }
            if let Some(m) = b.matrix {
                let m: Vec<String> = m.iter().map(|v| format!("{v:7.4}")).collect();
                line += &format!("  matrix {}", m.join(" "));
            }
            println!("{line}");
        }
        Reading::Glove(g) => {
            let raw: Vec<String> = g.raw.iter().map(|v| format!("{v:3}")).collect();
            println!("{:8.3}s glove {}", s.time, raw.join(" "));
            if let Some(c) = cal {
                let a: Vec<String> = c
                    .angles(&g.raw)
                    .iter()
                    .map(|a| format!("{:5.1}", a.to_degrees()))
                    .collect();
                println!("          deg   {}", a.join(" "));
            }
        }
        Reading::SpaceMouse(m) => println!(
            "{:8.3}s spacemouse t {:?} r {:?} buttons {:#x}",
            s.time, m.translation, m.rotation, m.buttons
        ),
        Reading::Vrpn(v) => println!("{:8.3}s vrpn {v}", s.time),
        Reading::Datagram { bytes } => println!("{:8.3}s datagram {} bytes", s.time, bytes.len()),
    }
}

fn mean_glove(path: &std::path::Path) -> Result<Vec<u8>> {
    let rec = Recording::read(path).map_err(|e| anyhow!(e))?;
    let s = rec
        .find("cyberglove")
        .ok_or_else(|| anyhow!("{}: no single glove stream", path.display()))?;
    let raws: Vec<Vec<u8>> = rec
        .readings(s)
        .map_err(|e| anyhow!(e))?
        .into_iter()
        .filter_map(|(_, r)| match r {
            Reading::Glove(g) => Some(g.raw),
            _ => None,
        })
        .collect();
    let first = raws
        .first()
        .ok_or_else(|| anyhow!("{}: no glove record", path.display()))?;
    let mut sum = vec![0.0; first.len()];
    for r in &raws {
        for (s, &v) in sum.iter_mut().zip(r) {
            *s += f64::from(v);
        }
    }
    Ok(sum
        .iter()
        .map(|s| (s / raws.len() as f64).round() as u8)
        .collect())
}

fn calibrate(c: CalibrateArgs) -> Result<ExitCode> {
    let flat = mean_glove(&c.flat)?;
    let fist = mean_glove(&c.fist)?;
    if flat.len() != fist.len() {
        bail!(
            "{} has {} sensors, {} has {}",
            c.flat.display(),
            flat.len(),
            c.fist.display(),
            fist.len()
        );
    }
    let side = match c.hand.as_str() {
        "right" => "r_",
        "left" => "l_",
        other => bail!("--hand must be right or left, got '{other}'"),
    };
    // Flat hand: every angle 0. Fist: each flexion sensor at its DOF's upper limit; the
    // abduction, arch and wrist sensors are not exercised and keep the flat reading as 0.
    let t = troupe_body::template("adult")?;
    let sk = t.instantiate(troupe_body::TemplateParams {
        height: t.default_height,
        mass: t.default_mass,
    })?;
    let names = troupe_drivers::cyberglove::sensor_names(flat.len());
    let fist_angles: Vec<f64> = names
        .iter()
        .map(|n| {
            let flexion = n.ends_with("_mpj")
                || n.ends_with("_pij")
                || n.ends_with("_dij")
                || n.ends_with("_ij")
                || *n == "thumb_rotation";
            let dof = troupe_drivers::performer::glove_dof_names(n, side)
                .first()
                .and_then(|d| sk.dof(d).ok());
            match (flexion, dof) {
                (true, Some(d)) => sk.dofs()[d].max,
                _ => 0.0,
            }
        })
        .collect();
    let cal = GloveCalibration::from_poses(&flat, &fist, &vec![0.0; flat.len()], &fist_angles)
        .map_err(|e| anyhow!(e))?;
    cal.save(&c.out).map_err(|e| anyhow!(e))?;
    println!("wrote {} ({} sensors)", c.out.display(), flat.len());
    Ok(ExitCode::SUCCESS)
}

/// `troupe emulate fob|cyberglove`.
pub fn emulate(a: EmulateArgs) -> Result<ExitCode> {
    let (kind, name) = match a.kind {
        EmulateKind::Fob => (DeviceKind::Fob, "fob"),
        EmulateKind::Cyberglove => (DeviceKind::CyberGlove, "cyberglove"),
        EmulateKind::Vmc => return emulate_vmc(&a),
    };
    if a.sensors != 18 && a.sensors != 22 {
        bail!("--sensors must be 18 or 22");
    }
    if a.birds == 0 || a.birds > 14 {
        bail!("--birds must be 1…14");
    }
    let motion = match &a.from {
        Some(p) => Motion::from_file(p, name, &a.joints, usize::from(a.birds), a.scale)
            .map_err(|e| anyhow!(e))?,
        None => Motion::Synthetic,
    };
    let options = EmulatorOptions {
        birds: a.birds,
        range: PositionRange::parse(&a.range).map_err(|e| anyhow!(e))?,
        sensors: a.sensors,
        rate_hz: a.rate.unwrap_or(100.0),
        motion,
    };
    let emu = emulator::start(kind, options, a.link.as_deref())
        .map_err(|e| anyhow!(e))
        .context("starting the emulator")?;
    println!("{}", emu.path());
    use std::io::Write;
    let _ = std::io::stdout().flush();
    eprintln!(
        "emulating a {name} on {} (pty {}); stop with Ctrl-C",
        emu.path(),
        emu.pty_path()
    );
    match a.seconds {
        Some(s) => {
            std::thread::sleep(Duration::from_secs_f64(s.max(0.0)));
            emu.stop();
        }
        None => emu.join(),
    }
    Ok(ExitCode::SUCCESS)
}

/// `troupe emulate vmc --from MOTION --to HOST:PORT`: sends the motion as a VMC stream in
/// real time, looped.
fn emulate_vmc(a: &EmulateArgs) -> Result<ExitCode> {
    use troupe_drivers::vmc::emulator::{send_motion, VmcMotion};
    let from = a
        .from
        .as_ref()
        .ok_or_else(|| anyhow!("emulate vmc needs --from MOTION.bvh or .trk"))?;
    let rate = a.rate.unwrap_or(60.0);
    if !(rate.is_finite() && rate > 0.0) {
        bail!("--rate must be a positive number of frames per second");
    }
    let motion = VmcMotion::load(from).map_err(|e| anyhow!(e))?;
    eprintln!(
        "sending {} ({:.2} s, looped) as VMC to {} at {rate} Hz; stop with Ctrl-C",
        from.display(),
        motion.duration(),
        a.to
    );
    let stop = std::sync::atomic::AtomicBool::new(false);
    let sent = send_motion(&motion, &a.to, rate, a.seconds, &stop).map_err(|e| anyhow!(e))?;
    eprintln!("sent {sent} frames");
    Ok(ExitCode::SUCCESS)
}

/// `troupe devices probe vmc --listen …`: prints what a VMC sender sends.
fn probe_vmc(listen: &str, samples: usize, timeout: Duration, json: bool) -> Result<ExitCode> {
    use troupe_drivers::vmc::{read_datagram, VmcCounters, VmcListener, VRM_BONES};
    let l = VmcListener::bind(listen, "probe", None).map_err(|e| anyhow!(e))?;
    eprintln!("listening for VMC on {}", l.from);
    let mut counters = VmcCounters::default();
    let (start, mut n) = (Instant::now(), 0);
    while n < samples && start.elapsed() < timeout {
        let Ok(d) = l.datagrams.recv_timeout(Duration::from_millis(50)) else {
            continue;
        };
        let p = read_datagram(&d.bytes, &mut counters);
        if p.is_empty() {
            // Garbage or another protocol: counted above, not a sample.
            continue;
        }
        let bones: Vec<&str> = VRM_BONES
            .iter()
            .zip(&p.pose.bones)
            .filter(|(_, t)| t.is_some())
            .map(|(b, _)| b.name)
            .collect();
        let hips = p.pose.bones[0].map(|t| t.translation.to_array());
        if json {
            let v = serde_json::json!({ "time": p.time, "loaded": p.loaded, "bones": bones,
                "root": p.pose.root.map(|t| t.translation.to_array()), "hips": hips });
            println!("{v}");
        } else {
            println!(
                "T {}  {} bones{}{}",
                p.time
                    .map(|t| format!("{t:8.3}"))
                    .unwrap_or_else(|| "       -".into()),
                bones.len(),
                p.pose
                    .root
                    .map(|t| format!("  root {:.3?}", t.translation.to_array()))
                    .unwrap_or_default(),
                hips.map(|h| format!("  hips {h:.3?}")).unwrap_or_default()
            );
        }
        n += 1;
    }
    let h = l.health.report();
    eprintln!(
        "{}: {} packets, {} malformed, {} unknown, {} ignored, {} invalid, {} unknown bones",
        h.state.name(),
        counters.packets,
        counters.malformed,
        counters.unknown,
        counters.ignored,
        counters.invalid,
        counters.unknown_bones
    );
    if n < samples {
        bail!(
            "got {n} of {samples} VMC packets on {} within {:.1} s",
            l.from,
            timeout.as_secs_f64()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Device support of a run: performers and, with `--record-devices`, the recorder. As an
/// observer it closes each tick for the latency measurement, and at the end reports every
/// device's health and closes the recording.
pub struct RunDevices {
    performers: troupe_drivers::performer::SharedPerformers,
    recorder: Option<std::sync::Arc<troupe_drivers::record::Recorder>>,
    record_path: Option<PathBuf>,
    /// SpaceMice moving objects (`troupe.devices.spacemouse`).
    space: troupe_drivers::space_move::SharedSpaceMice,
}

/// A Lua session with every action kind, `capture`, `troupe.performer` and the device
/// inputs; device streams are recorded to `record` when given. Observe the returned
/// [`RunDevices`] to measure latency and report health at the end.
pub fn session(
    config: troupe_scene::SceneConfig,
    limits: troupe_lua::ScriptLimits,
    record: Option<&std::path::Path>,
) -> Result<(troupe_lua::LuaSession, RunDevices)> {
    session_recording(config, limits, recorder(record, false)?, record)
}

/// The recorder of a run's inputs: to the file `record`, and tapped when `tap` (a Zenoh
/// leader sends its followers each tick's chunks); none when neither.
pub fn recorder(
    record: Option<&std::path::Path>,
    tap: bool,
) -> Result<Option<std::sync::Arc<troupe_drivers::record::Recorder>>> {
    use troupe_drivers::record::Recorder;
    let recorder = match record {
        Some(p) => Some(Recorder::create(p).map_err(|e| anyhow!(e))?),
        None if tap => Some(Recorder::tap_only()),
        None => None,
    };
    if tap {
        recorder.iter().for_each(Recorder::tap);
    }
    Ok(recorder.map(std::sync::Arc::new))
}

/// [`session`] with a recorder made by [`recorder`]; `record` names its file, if any.
pub fn session_recording(
    config: troupe_scene::SceneConfig,
    limits: troupe_lua::ScriptLimits,
    recorder: Option<std::sync::Arc<troupe_drivers::record::Recorder>>,
    record: Option<&std::path::Path>,
) -> Result<(troupe_lua::LuaSession, RunDevices)> {
    let kinds = troupe_actions::action_kinds();
    let mut session = troupe_lua::Director::session(config, kinds, limits)?;
    let devices = troupe_drivers::lua::install(&mut session, recorder.clone())?;
    Ok((
        session,
        RunDevices {
            performers: devices.performers,
            recorder,
            record_path: record.map(|p| p.to_path_buf()),
            space: devices.space_mice,
        },
    ))
}

impl troupe_scene::Observer for RunDevices {
    fn name(&self) -> String {
        "devices".into()
    }

    /// The samples used in this tick are now in a posture (latency).
    fn publish(
        &mut self,
        _scene: &troupe_scene::Scene,
        _events: &[troupe_scene::Event],
    ) -> troupe_scene::Result<()> {
        if let Ok(mut p) = self.performers.0.lock() {
            p.end_tick();
        }
        Ok(())
    }

    /// Device health and latency, and the recording closed.
    fn finish(&mut self, _scene: &troupe_scene::Scene) -> troupe_scene::Result<Option<String>> {
        let mut lines = Vec::new();
        if let Ok(p) = self.performers.0.lock() {
            for (who, dev, h) in p.health() {
                lines.push(format!(
                    "  device {who}.{dev}: {}, {} samples, {} resyncs, {} dropped bytes, {} dropped samples",
                    h.state.name(),
                    h.samples,
                    h.resyncs,
                    h.dropped_bytes,
                    h.dropped_samples
                ));
            }
            if let Some((m, p99)) = troupe_drivers::performer::median_p99(&p.latencies) {
                lines.push(format!(
                    "  sample-to-posture latency: median {:.2} ms, p99 {:.2} ms ({} samples)",
                    m * 1e3,
                    p99 * 1e3,
                    p.latencies.len()
                ));
            }
        }
        if let Ok(s) = self.space.0.lock() {
            for (name, h) in s.live_health() {
                lines.push(format!(
                    "  device {name} (spacemouse): {}, {} reports, {} bad reports{}",
                    h.state.name(),
                    h.samples,
                    h.resyncs,
                    h.last_error.map(|e| format!(" ({e})")).unwrap_or_default()
                ));
            }
        }
        if let Some(r) = &self.recorder {
            r.finish()
                .map_err(|e| troupe_scene::Error::Invalid(e.to_string()))?;
        }
        if let Some(path) = &self.record_path {
            lines.push(format!("recorded the device streams to {}", path.display()));
        }
        Ok((!lines.is_empty()).then(|| lines.join("\n")))
    }
}
