//! `troupe view --zenoh PREFIX`: a render node. It asks the publishing troupe for its
//! actors (template, height, DOF names), builds them, and shows each tick the postures it
//! receives, in a window or headless into PNG frames (docs/distributed.md).

use super::{has_display, render_options, write_frames, ViewArgs};
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;
use troupe_net::subscriber::{actor_bodies, ActorBody};
use troupe_net::{Endpoints, PoseFeed, SceneKeys};
use troupe_scene::pacing::Pacer;
use troupe_scene::{ActorDesc, Input, Scene, SceneConfig, Session};
use troupe_viewer::{run_window, Camera, Frame, FrameWriter, WindowOptions};

/// How long a render node waits for the scene to answer.
const MEET_TIMEOUT: Duration = Duration::from_secs(30);

/// Options of a render node.
#[derive(Args, Clone, Debug, Default)]
pub struct RemoteViewArgs {
    /// Show the scene published under PREFIX (`troupe run --zenoh --zenoh-prefix PREFIX`)
    /// live instead of a recording.
    #[arg(long, value_name = "PREFIX")]
    pub zenoh: Option<String>,
    /// With --zenoh: an endpoint to connect to, e.g. tcp/10.0.0.5:7447 (repeatable).
    #[arg(long = "zenoh-connect", value_name = "ENDPOINT", requires = "zenoh")]
    pub connect: Vec<String>,
}

/// Sets every remote actor's DOFs to the newest posture received (an input).
struct RemotePoses {
    feed: PoseFeed,
    /// Published actor names, in the order of the scene's actors.
    actors: Vec<String>,
}

impl Input for RemotePoses {
    fn name(&self) -> String {
        "--zenoh postures".into()
    }

    fn poll(&mut self, scene: &mut Scene) -> troupe_scene::Result<()> {
        let mut refused = None;
        for m in self.feed.received().try_iter() {
            let Some(actor) = self.actors.iter().position(|a| *a == m.actor) else {
                continue;
            };
            match m.posture {
                Ok(p) => {
                    let values: Vec<(usize, f64)> = p.values.into_iter().enumerate().collect();
                    scene.set_dofs(actor, &values)?;
                }
                Err(e) => refused = Some(format!("{}: {e}", m.actor)),
            }
        }
        match refused {
            Some(e) => Err(troupe_scene::Error::Invalid(e)),
            None => Ok(()),
        }
    }
}

/// Runs a render node on the scene under `prefix`.
pub fn run(args: &ViewArgs, prefix: &str) -> Result<ExitCode> {
    let size = troupe_viewer::parse_size(&args.size)?;
    let keys = SceneKeys::new(prefix).context("--zenoh")?;
    let net = Endpoints {
        connect: args.remote.connect.clone(),
        listen: vec![],
    }
    .open()?;
    let feed = PoseFeed::subscribe(&net, &keys)?;
    let bodies = meet(&net, &keys)?;
    let mut scene = Scene::new(SceneConfig {
        rate: args.rate,
        ..SceneConfig::default()
    })?;
    for body in &bodies {
        let desc = ActorDesc {
            template: body.template.clone(),
            height: body.height,
            ..ActorDesc::new(body.actor.clone())
        };
        let actor = scene.add_actor(&desc)?;
        let own: Vec<&str> = scene.actors()[actor]
            .skeleton
            .dofs()
            .iter()
            .map(|d| d.name.as_str())
            .collect();
        if own != body.dofs.iter().map(String::as_str).collect::<Vec<_>>() {
            bail!(
                "{prefix}: actor {} has other DOFs than template {} here (another troupe version?)",
                body.actor,
                body.template
            );
        }
    }
    let camera: Camera = match &args.camera {
        Some(c) => c.parse()?,
        None => Camera::fit(),
    };
    let mut session = Session::new(scene);
    session.add_input(Box::new(RemotePoses {
        feed,
        actors: bodies.iter().map(|b| b.actor.clone()).collect(),
    }));
    let headless_dir = match (&args.frames, has_display()) {
        (Some(dir), _) => Some(dir.clone()),
        (None, false) => Some(PathBuf::from("frames")),
        (None, true) => None,
    };
    if let Some(dir) = headless_dir {
        let seconds = args.seconds.unwrap_or(10.0).max(0.0);
        let mut writer = FrameWriter::new(&dir, size, camera, args.every)?;
        writer
            .renderer_mut()
            .set_options(render_options(args.look, args.bones, !args.no_labels));
        writer.renderer_mut().set_multisampling(!args.no_msaa);
        // Live: one tick per tick period, showing what has arrived by then.
        session.observe(Pacer::new(Duration::from_secs_f64(1.0 / args.rate)));
        return write_frames(session, writer, seconds);
    }
    let options = WindowOptions {
        title: format!("troupe view --zenoh {prefix}"),
        size,
        camera,
        render: render_options(args.look, args.bones, !args.no_labels),
        tick_seconds: 1.0 / args.rate,
        close_after_frames: None,
    };
    run_window(options, move || {
        // Postures come from the network; no observer can fail here.
        let _ = session.tick();
        Frame::from_scene(session.scene())
    })
    .map_err(|e| anyhow!(e))?;
    Ok(ExitCode::SUCCESS)
}

/// Asks for the actors until the scene answers.
fn meet(net: &troupe_net::zenoh::Session, keys: &SceneKeys) -> Result<Vec<ActorBody>> {
    let deadline = std::time::Instant::now() + MEET_TIMEOUT;
    loop {
        let bodies = actor_bodies(net, keys, Duration::from_millis(500))?;
        if !bodies.is_empty() {
            return Ok(bodies);
        }
        if std::time::Instant::now() > deadline {
            bail!(
                "no scene answered on {} within {} s",
                keys.all_dofs(),
                MEET_TIMEOUT.as_secs()
            );
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}
