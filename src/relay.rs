//! `troupe relay KIND --port PATH --key KEY --zenoh-…`: serves a device on Zenoh from the
//! machine it is plugged into (a Flock of Birds or a CyberGlove on a serial port, a
//! SpaceMouse on hidraw, a VRPN server it reaches, a VMC sender's UDP datagrams); the
//! simulation host names it with `zenoh = KEY` in a performer's device table or
//! `troupe.devices.spacemouse` (docs/distributed.md, "Remote device hosts").

use anyhow::{bail, Context, Result};
use clap::Args;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use troupe_drivers::device::Port;
use troupe_net::relay::{serve, serve_on_demand, RelayStats};
use troupe_net::Endpoints;

/// Options of `troupe relay`.
#[derive(Args)]
pub struct RelayArgs {
    /// The device kind: fob, cyberglove (serial ports), spacemouse (hidraw), vrpn (a
    /// VRPN server this machine reaches, --device) or vmc (a VMC sender's UDP datagrams,
    /// --listen).
    pub kind: String,
    /// The serial port the device is on; for a SpaceMouse, its hidraw path (default: the
    /// first SpaceMouse found).
    #[arg(long)]
    pub port: Option<String>,
    /// VRPN: the server's device, `Tracker0@host[:port]` (or `Tracker0@tcp://host:port`).
    #[arg(long)]
    pub device: Option<String>,
    /// VMC: the UDP address the sender sends to (host:port).
    #[arg(long, default_value = "0.0.0.0:39539")]
    pub listen: String,
    /// Baud rate.
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// The key the device is served under (a performer names it with `zenoh = KEY`).
    #[arg(long)]
    pub key: String,
    /// A Zenoh endpoint to connect to, e.g. tcp/10.0.0.5:7447 (repeatable).
    #[arg(long, value_name = "ENDPOINT")]
    pub zenoh_connect: Vec<String>,
    /// A Zenoh endpoint to listen on, e.g. tcp/0.0.0.0:7448 (repeatable).
    #[arg(long, value_name = "ENDPOINT")]
    pub zenoh_listen: Vec<String>,
    /// Stop after this many seconds (default: run until killed).
    #[arg(long)]
    pub seconds: Option<f64>,
}

/// Serves the device until the time is up, reopening its port when it fails.
pub fn run(args: RelayArgs) -> Result<ExitCode> {
    match (args.kind.as_str(), &args.port, &args.device) {
        ("fob" | "cyberglove", Some(_), _)
        | ("spacemouse" | "vmc", _, _)
        | ("vrpn", _, Some(_)) => {}
        ("fob" | "cyberglove", None, _) => {
            bail!("troupe relay {}: --port is required", args.kind)
        }
        ("vrpn", _, None) => bail!("troupe relay vrpn: --device Tracker0@host is required"),
        (other, _, _) => bail!(
            "troupe relay {other}: relays serve fob, cyberglove (serial ports), spacemouse \
             (hidraw), vrpn (a VRPN server) and vmc (a VMC sender's UDP datagrams); OSC \
             senders send to the simulation host's UDP port directly (docs/distributed.md)"
        ),
    }
    troupe_net::SceneKeys::new(&args.key).context("--key")?;
    if args.kind == "vmc" {
        // An address that cannot be bound now will not be later: refuse it at once.
        troupe_drivers::vmc::UdpDatagrams::bind(&args.listen)
            .with_context(|| format!("troupe relay vmc --listen {}", args.listen))?;
    }
    let session = Endpoints {
        connect: args.zenoh_connect.clone(),
        listen: args.zenoh_listen.clone(),
    }
    .open()?;
    let stop = Arc::new(AtomicBool::new(false));
    if let Some(s) = args.seconds {
        let stop = stop.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_secs_f64(s.max(0.0)));
            stop.store(true, Ordering::Release);
        });
    }
    let port_name = match args.kind.as_str() {
        "vmc" => format!("udp {}", args.listen),
        _ => (args.device.as_deref().or(args.port.as_deref()))
            .unwrap_or("(the first SpaceMouse)")
            .to_string(),
    };
    println!("relaying {} {port_name} on {}", args.kind, args.key);
    let started = Instant::now();
    let mut total = RelayStats::default();
    while !stop.load(Ordering::Acquire) {
        let served = if args.kind == "vrpn" {
            // A VRPN server describes its senders once per connection: connect when the
            // simulation host's client first speaks, so it sees the descriptions.
            let mut connect = || {
                open(&args)
                    .map(Some)
                    .map_err(|e| troupe_net::NetError::Open(format!("{e:#}")))
            };
            serve_on_demand(&session, &args.key, &mut connect, &stop).map_err(anyhow::Error::new)
        } else {
            open(&args).and_then(|mut port| Ok(serve(&session, &args.key, &mut port, &stop)?))
        };
        match served {
            Ok(stats) => add(&mut total, stats),
            Err(e) => {
                tracing::warn!("relay {}: {e:#}; retrying", args.key);
                std::thread::sleep(Duration::from_millis(500));
            }
        }
    }
    println!(
        "relayed {} chunks ({} bytes) and {} commands in {:.1} s",
        total.chunks,
        total.bytes,
        total.commands,
        started.elapsed().as_secs_f64()
    );
    Ok(ExitCode::SUCCESS)
}

/// The device's port: a serial port; a SpaceMouse's hidraw node (one report a read, each
/// put as one chunk, which is one read on the simulation host); a connection to a VRPN
/// server, cookies exchanged (whole messages a read; the simulation host's VRPN client
/// describes its senders through the relay); or a UDP socket a VMC sender sends to (one
/// datagram a read, a chunk each, read whole on the simulation host).
fn open(args: &RelayArgs) -> Result<Box<dyn Port>> {
    use troupe_drivers::vrpn::{DatagramCounters, DeviceName, VrpnPort, HANDSHAKE_TIMEOUT};
    match (args.kind.as_str(), &args.port, &args.device) {
        ("vmc", _, _) => Ok(Box::new(troupe_drivers::vmc::UdpDatagrams::bind(
            &args.listen,
        )?)),
        ("spacemouse", path, _) => Ok(troupe_drivers::spacemouse::open_spacemouse(
            path.as_deref(),
        )?),
        ("vrpn", _, Some(device)) => {
            let name = DeviceName::parse(device)?;
            let counters = Arc::new(DatagramCounters::default());
            Ok(Box::new(VrpnPort::connect(
                &name,
                HANDSHAKE_TIMEOUT,
                counters,
            )?))
        }
        (_, path, _) => Ok(troupe_drivers::device::open_serial(
            path.as_deref().unwrap_or(""),
            args.baud,
        )?),
    }
}

fn add(total: &mut RelayStats, s: RelayStats) {
    total.chunks += s.chunks;
    total.bytes += s.bytes;
    total.commands += s.commands;
}
