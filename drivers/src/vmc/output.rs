//! VMC out: troupe as a VMC Performer sending actors to Marionettes (EVMC4U, VMC4UE,
//! VMC4B, Godot's VMC tracker). Each stream sends one actor to one UDP address, one
//! bundle per frame, at its own rate in scene time whatever the tick rate.

use crate::osc::OscError;
use crate::vmc::message::frame_bundle;
use crate::vmc::rig::VmcRig;
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::sync::{Arc, Mutex};
use troupe_scene::Scene;

/// The port Marionettes listen on by default.
pub const MARIONETTE_PORT: u16 = 39539;

/// The default frame rate, Hz.
pub const DEFAULT_RATE: f64 = 60.0;

/// A VMC stream that cannot be opened.
#[derive(Debug, thiserror::Error)]
pub enum VmcOutError {
    /// The address does not resolve or the socket cannot be made.
    #[error(transparent)]
    Osc(#[from] OscError),
    /// The rate is not a positive number.
    #[error(
        "VMC out to {target}: the rate must be a positive number of frames per second, got {rate}"
    )]
    Rate {
        /// The address given.
        target: String,
        /// The rate given.
        rate: f64,
    },
}

/// One actor sent to one address.
pub struct VmcStream {
    socket: UdpSocket,
    target: SocketAddr,
    /// The actor's name; `None`: the scene's first actor.
    actor: Option<String>,
    period: f64,
    /// Scene time of the next frame.
    next: f64,
    rig: Option<(usize, VmcRig)>,
    /// Frames sent.
    pub sent: u64,
    /// Sends that failed.
    pub failures: u64,
}

/// Resolves `host:port`, or `host` alone with the Marionette port.
fn resolve(target: &str) -> Result<SocketAddr, OscError> {
    let with_port = if target
        .rsplit_once(':')
        .is_some_and(|(_, p)| p.parse::<u16>().is_ok())
    {
        target.to_string()
    } else {
        format!("{target}:{MARIONETTE_PORT}")
    };
    with_port
        .to_socket_addrs()
        .map_err(|source| OscError::Address {
            target: target.to_string(),
            source,
        })?
        .next()
        .ok_or_else(|| OscError::Unresolved(target.to_string()))
}

impl VmcStream {
    /// A stream of `actor` (default the first) to `target` (`host[:port]`, default port
    /// 39539) at `rate` frames per second of scene time.
    pub fn new(target: &str, actor: Option<String>, rate: f64) -> Result<VmcStream, VmcOutError> {
        if !(rate.is_finite() && rate > 0.0) {
            return Err(VmcOutError::Rate {
                target: target.to_string(),
                rate,
            });
        }
        let addr = resolve(target)?;
        let bind = if addr.is_ipv4() {
            "0.0.0.0:0"
        } else {
            "[::]:0"
        };
        let socket = UdpSocket::bind(bind).map_err(OscError::Socket)?;
        Ok(VmcStream {
            socket,
            target: addr,
            actor,
            period: 1.0 / rate,
            next: 0.0,
            rig: None,
            sent: 0,
            failures: 0,
        })
    }

    /// Parses `HOST:PORT[=ACTOR]` (what `--vmc-out` takes).
    pub fn parse(spec: &str, rate: f64) -> Result<VmcStream, VmcOutError> {
        match spec.split_once('=') {
            Some((to, actor)) => VmcStream::new(to, Some(actor.to_string()), rate),
            None => VmcStream::new(spec, None, rate),
        }
    }

    /// The address frames go to.
    pub fn target(&self) -> SocketAddr {
        self.target
    }

    /// The bundle bytes of the actor's frame now, or an error naming a missing actor.
    pub fn frame(&mut self, scene: &Scene) -> Result<Vec<u8>, String> {
        let i = match &self.actor {
            Some(name) => scene
                .actors()
                .iter()
                .position(|a| &a.name == name)
                .ok_or_else(|| format!("no actor '{name}' to send"))?,
            None if scene.actors().is_empty() => return Err("no actor to send".into()),
            None => 0,
        };
        if self.rig.as_ref().is_none_or(|(a, _)| *a != i) {
            let rig = VmcRig::new(scene.actors()[i].skeleton.clone()).map_err(|e| e.to_string())?;
            self.rig = Some((i, rig));
        }
        let (_, rig) = self.rig.as_ref().expect("set above");
        let pose = rig.pose(&scene.states()[i].globals);
        rosc::encoder::encode(&frame_bundle(&pose, scene.time())).map_err(|e| e.to_string())
    }

    /// Sends a frame if one is due at the scene's time; a failed send is counted.
    pub fn publish(&mut self, scene: &Scene) -> Result<(), String> {
        let t = scene.time();
        if t + 1e-9 < self.next {
            return Ok(());
        }
        while self.next <= t + 1e-9 {
            self.next += self.period;
        }
        let bytes = self.frame(scene)?;
        match self.socket.send_to(&bytes, self.target) {
            Ok(_) => self.sent += 1,
            Err(e) => {
                if self.failures == 0 {
                    tracing::warn!(
                        "VMC out to {}: {e} (further failures are counted)",
                        self.target
                    );
                }
                self.failures += 1;
            }
        }
        Ok(())
    }
}

/// Every VMC stream of a run, as a session observer (`--vmc-out`).
#[derive(Default)]
pub struct VmcOut {
    /// The streams.
    pub streams: Vec<VmcStream>,
}

impl VmcOut {
    fn publish_all(&mut self, scene: &Scene) -> troupe_scene::Result<()> {
        for s in &mut self.streams {
            s.publish(scene)
                .map_err(|message| troupe_scene::Error::Observer {
                    observer: format!("VMC out to {}", s.target),
                    message,
                })?;
        }
        Ok(())
    }

    fn summary(&self) -> Option<String> {
        let lines: Vec<String> = self
            .streams
            .iter()
            .map(|s| {
                format!(
                    "  VMC out to {} ({}): {} frames{}",
                    s.target,
                    s.actor.as_deref().unwrap_or("first actor"),
                    s.sent,
                    if s.failures > 0 {
                        format!(", {} sends failed", s.failures)
                    } else {
                        String::new()
                    }
                )
            })
            .collect();
        (!lines.is_empty()).then(|| lines.join("\n"))
    }
}

impl troupe_scene::Observer for VmcOut {
    fn name(&self) -> String {
        "--vmc-out".into()
    }

    fn start(&mut self, scene: &Scene) -> troupe_scene::Result<()> {
        self.publish_all(scene)
    }

    fn publish(
        &mut self,
        scene: &Scene,
        _events: &[troupe_scene::Event],
    ) -> troupe_scene::Result<()> {
        self.publish_all(scene)
    }

    fn finish(&mut self, _scene: &Scene) -> troupe_scene::Result<Option<String>> {
        Ok(self.summary())
    }
}

/// The streams `troupe.vmc_out{…}` opens, shared by the Lua API and its observer.
#[derive(Clone, Default)]
pub struct SharedVmcOut(pub Arc<Mutex<VmcOut>>);

impl troupe_scene::Observer for SharedVmcOut {
    fn name(&self) -> String {
        "troupe.vmc_out".into()
    }

    fn publish(
        &mut self,
        scene: &Scene,
        _events: &[troupe_scene::Event],
    ) -> troupe_scene::Result<()> {
        match self.0.lock() {
            Ok(mut out) => out.publish_all(scene),
            Err(_) => Err(troupe_scene::Error::Invalid("VMC out lock poisoned".into())),
        }
    }

    fn finish(&mut self, _scene: &Scene) -> troupe_scene::Result<Option<String>> {
        Ok(self.0.lock().ok().and_then(|o| o.summary()))
    }
}
