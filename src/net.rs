//! `--zenoh …` on `troupe run`: publishing the scene on Zenoh, or following a leader
//! (docs/distributed.md).

use anyhow::{bail, Context, Result};
use clap::Args;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use troupe_drivers::device::{DeviceError, Port, RemotePorts};
use troupe_drivers::record::{DeviceReplay, Recorder};
use troupe_lua::{LuaSession, LuaSessionExt};
use troupe_net::follow::{FollowCheck, FollowInput, Leader};
use troupe_net::relay::ZenohPort;
use troupe_net::{Endpoints, MessageInput, SceneKeys, ScenePublisher};
use troupe_scene::{Event, Observer, Scene, SceneConfig};

/// How long a leader waits for a follower, and a follower for a leader.
const MEET_TIMEOUT: Duration = Duration::from_secs(30);

/// Options for publishing a run on Zenoh or following one.
#[derive(Args, Clone, Debug, Default)]
pub struct ZenohArgs {
    /// Publish the scene on Zenoh: every actor's posture each tick, object poses, action
    /// events, messages (keys in docs/distributed.md). Never blocks the tick.
    #[arg(long)]
    pub zenoh: bool,
    /// A Zenoh endpoint to connect to, e.g. tcp/10.0.0.5:7447 (repeatable). Any endpoint
    /// opens a network session, which performers' relayed devices (`zenoh = KEY`) use.
    #[arg(long, value_name = "ENDPOINT")]
    pub zenoh_connect: Vec<String>,
    /// A Zenoh endpoint to listen on, e.g. tcp/0.0.0.0:7447 (repeatable).
    #[arg(long, value_name = "ENDPOINT")]
    pub zenoh_listen: Vec<String>,
    /// The key prefix the scene is published under.
    #[arg(long, value_name = "KEY", default_value = "troupe/scene")]
    pub zenoh_prefix: String,
    /// With --zenoh: before the first tick, wait (up to 30 s) for a follower.
    #[arg(long, requires = "zenoh")]
    pub zenoh_await_followers: bool,
    /// Follow the leader publishing under PREFIX: run this scene with the leader's seed
    /// and inputs (its devices' samples and messages from outside, at their ticks),
    /// compare every posture with the leader's, fail naming the first tick that differs.
    #[arg(long, value_name = "PREFIX", conflicts_with_all = ["zenoh", "replay_devices"])]
    pub zenoh_follow: Option<String>,
}

/// What `--zenoh` attaches to a session.
pub struct Zenoh {
    /// The network session, when any option asked for one (relayed devices use it).
    session: Option<troupe_net::zenoh::Session>,
    publisher: Option<(ScenePublisher, MessageInput)>,
    /// A follower's input and check, and the replay of the leader's inputs it feeds.
    follower: Option<(FollowInput, FollowCheck, DeviceReplay)>,
    /// Delays of relayed device bytes, source to read (microseconds).
    relay_delays: Arc<Mutex<Vec<u64>>>,
}

impl ZenohArgs {
    fn endpoints(&self) -> Endpoints {
        Endpoints {
            connect: self.zenoh_connect.clone(),
            listen: self.zenoh_listen.clone(),
        }
    }

    /// Opens what these options ask for, before the scene loads (a bad endpoint is
    /// refused before devices open). A follower meets its leader here and takes the
    /// leader's seed: the returned configuration is the one to run with.
    pub fn open(&self, mut config: SceneConfig) -> Result<(SceneConfig, Zenoh)> {
        let networked = self.zenoh
            || self.zenoh_follow.is_some()
            || !self.zenoh_connect.is_empty()
            || !self.zenoh_listen.is_empty();
        let session = if networked {
            Some(self.endpoints().open()?)
        } else {
            None
        };
        let none = Zenoh {
            session: session.clone(),
            publisher: None,
            follower: None,
            relay_delays: Arc::default(),
        };
        let Some(session) = session else {
            return Ok((config, none));
        };
        if let Some(prefix) = &self.zenoh_follow {
            let keys = SceneKeys::new(prefix).context("--zenoh-follow")?;
            let leader = Leader::subscribe(session, keys)?;
            let scene = leader.scene(MEET_TIMEOUT)?;
            if scene.rate != config.rate {
                bail!(
                    "--zenoh-follow {prefix}: the leader ticks at {} Hz, this run at {} Hz (--rate)",
                    scene.rate,
                    config.rate
                );
            }
            config.seed = scene.seed;
            let (input, check) = leader.into_parts();
            let replay = DeviceReplay::live(&format!("--zenoh-follow {prefix}"));
            let follower = Some((input, check, replay));
            return Ok((config, Zenoh { follower, ..none }));
        }
        if !self.zenoh {
            return Ok((config, none));
        }
        let keys = SceneKeys::new(&self.zenoh_prefix).context("--zenoh-prefix")?;
        let input = MessageInput::new(session.clone());
        let mut publisher = ScenePublisher::new(session, keys)?;
        if self.zenoh_await_followers {
            publisher.await_followers(MEET_TIMEOUT);
        }
        Ok((
            config,
            Zenoh {
                publisher: Some((publisher, input)),
                ..none
            },
        ))
    }
}

impl Zenoh {
    /// Whether each tick's inputs are sent to followers (a leader publishing).
    pub fn replicates(&self) -> bool {
        self.publisher.is_some()
    }

    /// Lets the scene's performers name devices served by a relay (`zenoh = KEY`), and
    /// makes a follower's devices read the leader's: call before the scene loads.
    pub fn install(&self, session: &LuaSession) {
        if let Some((_, _, replay)) = &self.follower {
            session.lua().set_app_data(replay.clone());
        }
        if let Some(net) = &self.session {
            let net = net.clone();
            let delays = self.relay_delays.clone();
            let open = move |key: &str| -> Result<Box<dyn Port>, DeviceError> {
                ZenohPort::open(&net, key)
                    .map(|p| Box::new(p.measure_delays(delays.clone())) as Box<dyn Port>)
                    .map_err(|e| DeviceError::Remote {
                        key: key.to_string(),
                        message: e.to_string(),
                    })
            };
            session.lua().set_app_data(RemotePorts(Arc::new(open)));
        }
    }

    /// Attaches the publisher (an observer, sending followers what `recorder` taps) and
    /// the message input, or the follower's input (first: the replayed devices read what
    /// it brings), its replayed messages and its check, to a session.
    pub fn attach(self, session: &mut LuaSession, recorder: Option<Arc<Recorder>>) {
        if self.session.is_some() {
            session.observe(RelayDelays(self.relay_delays));
        }
        if let Some((mut publisher, input)) = self.publisher {
            if let Some(recorder) = recorder {
                publisher.replicate(Box::new(move || recorder.take_tap()));
            }
            session.observe(publisher);
            session.add_input(Box::new(input));
        }
        if let Some((mut input, check, replay)) = self.follower {
            let fed = replay.clone();
            input.replay_into(Box::new(move |chunks| fed.feed(chunks)));
            session.add_input_first(Box::new(input));
            session.add_input(Box::new(replay.messages()));
            session.observe(check);
        }
    }
}

/// Reports how long relayed device bytes took from their source to this host.
struct RelayDelays(Arc<Mutex<Vec<u64>>>);

impl Observer for RelayDelays {
    fn name(&self) -> String {
        "relayed devices".into()
    }

    fn publish(&mut self, _: &Scene, _: &[Event]) -> troupe_scene::Result<()> {
        Ok(())
    }

    fn finish(&mut self, _: &Scene) -> troupe_scene::Result<Option<String>> {
        let mut d = self.0.lock().map(|d| d.clone()).unwrap_or_default();
        if d.is_empty() {
            return Ok(None);
        }
        d.sort_unstable();
        let at = |q: f64| d[((d.len() - 1) as f64 * q).round() as usize] as f64 / 1e3;
        Ok(Some(format!(
            "  relay-to-simulation delay of device bytes: median {:.2} ms, p99 {:.2} ms ({} chunks)",
            at(0.5),
            at(0.99),
            d.len()
        )))
    }
}
