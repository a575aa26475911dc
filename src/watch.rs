//! Hot reload for `troupe run SCENE --view --watch`: when the scene file, or any file it
//! read (a module from its folder, a motion file), changes, the scene is loaded afresh and
//! run back to the simulated time it had reached. Same scene, seed and tick count give the
//! same state, so the reloaded scene continues as if it had been written that way from
//! the start. A broken edit keeps the last good scene and shows its error over it.
//!
//! [`Reloader`] holds that logic apart from the window, so that it runs (and is tested)
//! headless too.

use anyhow::Result;
use std::path::PathBuf;
use std::time::SystemTime;
use troupe_lua::{LuaSession, LuaSessionExt};
use troupe_scene::RunLimit;

/// What tells a file changed: its modification time and length (`None`: it is missing).
type Stamp = Option<(SystemTime, u64)>;

fn stamp(path: &std::path::Path) -> Stamp {
    let meta = std::fs::metadata(path).ok()?;
    Some((meta.modified().ok()?, meta.len()))
}

/// Reloads a scene when its files change.
pub struct Reloader<F: FnMut() -> Result<LuaSession>> {
    /// Makes an empty session, with the options of the run.
    make: F,
    scene: PathBuf,
    /// The files the last load read, with their stamps then.
    watched: Vec<(PathBuf, Stamp)>,
    /// Why the last reload failed, until one succeeds.
    error: Option<String>,
}

impl<F: FnMut() -> Result<LuaSession>> Reloader<F> {
    /// Loads `scene` into a session made by `make`; a scene that does not load is an error
    /// here (there is no last good scene yet).
    pub fn start(scene: PathBuf, mut make: F) -> Result<(Reloader<F>, LuaSession)> {
        let session = load(&mut make, &scene, 0)?;
        let mut reloader = Reloader {
            make,
            scene,
            watched: Vec::new(),
            error: None,
        };
        reloader.watch(&session);
        Ok((reloader, session))
    }

    fn watch(&mut self, session: &LuaSession) {
        let mut files = session.script().loaded_files();
        if !files.contains(&self.scene) {
            files.insert(0, self.scene.clone());
        }
        files.dedup();
        self.watched = files.into_iter().map(|f| (f.clone(), stamp(&f))).collect();
    }

    /// The files watched.
    pub fn files(&self) -> Vec<PathBuf> {
        self.watched.iter().map(|(f, _)| f.clone()).collect()
    }

    /// Whether a watched file changed (or appeared, or vanished) since the last load.
    pub fn changed(&self) -> bool {
        self.watched.iter().any(|(f, s)| stamp(f) != *s)
    }

    /// Loads the scene afresh and runs it to the tick `current` has reached. On success the
    /// new session replaces the old one; a scene that fails to load or to run keeps the
    /// old one, and its error is kept for [`Reloader::error`] until a reload succeeds.
    pub fn reload(&mut self, current: &LuaSession) -> Option<LuaSession> {
        let ticks = current.scene().tick();
        // Stamps taken before loading: an edit made while it loads is seen next time.
        let stamps: Vec<(PathBuf, Stamp)> = self
            .watched
            .iter()
            .map(|(f, _)| (f.clone(), stamp(f)))
            .collect();
        match load(&mut self.make, &self.scene, ticks) {
            Ok(session) => {
                self.error = None;
                self.watch(&session);
                Some(session)
            }
            Err(e) => {
                self.error = Some(format!("{e:#}"));
                self.watched = stamps;
                None
            }
        }
    }

    /// Why the last reload failed, while the last good scene is shown.
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// The picture of `session`, with the failed reload's error over it.
    pub fn frame(&self, session: &LuaSession) -> troupe_viewer::Frame {
        let mut frame = troupe_viewer::Frame::from_scene(session.scene());
        if let Some(e) = &self.error {
            frame.notice.push(format!(
                "reload of {} failed; showing the last good scene:",
                self.scene.display()
            ));
            frame.notice.extend(
                e.lines()
                    .filter(|l| !l.trim().is_empty())
                    .take(6)
                    .map(|l| l.replace('\t', "  ")),
            );
        }
        frame
    }
}

/// What a watched run needs of `troupe run`'s options.
pub struct WatchedRun {
    /// The scene file.
    pub scene: PathBuf,
    /// `--chunk`.
    pub chunk: Option<usize>,
    /// How many ticks the run may go (`--ticks`, `--seconds` or `--max-seconds`).
    pub ticks: u64,
}

/// `troupe run SCENE --view --watch`: the window shows the scene; every 300 ms of wall time
/// its files are looked at, and a change reloads it (see [`Reloader`]).
pub fn view(
    run: WatchedRun,
    config: troupe_scene::SceneConfig,
    limits: troupe_lua::ScriptLimits,
    size: (u32, u32),
    camera: troupe_viewer::Camera,
) -> Result<std::process::ExitCode> {
    use std::sync::{Arc, Mutex};
    use std::time::{Duration, Instant};
    let chunk = run.chunk;
    let make = move || -> Result<LuaSession> {
        let (mut session, devices) = crate::devices::session(config, limits, None)?;
        session.scene_mut().set_chunk_size(chunk);
        session.observe(devices);
        Ok(session)
    };
    let (reloader, session) = Reloader::start(run.scene.clone(), make)?;
    println!(
        "watching {} for changes",
        reloader
            .files()
            .iter()
            .map(|f| f.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    let max_ticks = run.ticks;
    struct Watched<F: FnMut() -> Result<LuaSession>> {
        reloader: Reloader<F>,
        session: LuaSession,
        looked: Instant,
    }
    let shared = Arc::new(Mutex::new(Watched {
        reloader,
        session,
        looked: Instant::now(),
    }));
    let sim = shared.clone();
    let options = troupe_viewer::WindowOptions {
        title: format!("troupe run {} (watching)", run.scene.display()),
        size,
        camera,
        tick_seconds: 1.0 / config.rate,
        ..Default::default()
    };
    let shown = troupe_viewer::run_window(options, move || {
        let mut w = sim.lock().unwrap_or_else(|e| e.into_inner());
        let w = &mut *w;
        if w.looked.elapsed() >= Duration::from_millis(300) {
            w.looked = Instant::now();
            if w.reloader.changed() {
                match w.reloader.reload(&w.session) {
                    Some(fresh) => {
                        println!(
                            "reloaded {} at t = {:.2} s",
                            args_scene(&fresh),
                            fresh.scene().time()
                        );
                        w.session = fresh;
                    }
                    None => eprintln!(
                        "troupe: reload failed, keeping the last good scene: {}",
                        w.reloader.error().unwrap_or_default()
                    ),
                }
            }
        }
        if w.session.scene().tick() < max_ticks && w.reloader.error().is_none() {
            if let Err(e) = w.session.tick() {
                eprintln!("troupe: {e}");
            }
        }
        w.reloader.frame(&w.session)
    });
    shown?;
    Ok(std::process::ExitCode::SUCCESS)
}

/// The scene file's name as the log shows it.
fn args_scene(session: &LuaSession) -> String {
    session
        .script()
        .loaded_files()
        .first()
        .map(|f| f.display().to_string())
        .unwrap_or_default()
}

/// A session made by `make`, the scene loaded and run for `ticks` ticks.
fn load(
    make: &mut impl FnMut() -> Result<LuaSession>,
    scene: &std::path::Path,
    ticks: u64,
) -> Result<LuaSession> {
    let mut session = make()?;
    session
        .load_file(scene)
        .map_err(|e| anyhow::anyhow!("loading {}: {e}", scene.display()))?;
    session.run(RunLimit {
        ticks,
        until_idle: false,
    })?;
    Ok(session)
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_lua::{Director, ScriptLimits};
    use troupe_scene::SceneConfig;

    fn make() -> Result<LuaSession> {
        Ok(Director::session(
            SceneConfig::default(),
            troupe_actions::action_kinds(),
            ScriptLimits::default(),
        )?)
    }

    fn folder(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("troupe-watch-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// Writes `text` to `path` so that its stamp surely changes (length or time).
    fn write(path: &std::path::Path, text: &str) {
        let before = stamp(path);
        std::fs::write(path, text).unwrap();
        if stamp(path) == before {
            std::thread::sleep(std::time::Duration::from_millis(20));
            std::fs::write(path, text).unwrap();
        }
    }

    fn elbow(s: &LuaSession) -> f64 {
        let ann = s.scene().actor_index("ann").unwrap();
        let d = s.scene().actors()[ann]
            .skeleton
            .dof("r_elbow_flexion")
            .unwrap();
        s.scene().states()[ann].q[d]
    }

    const SCENE: &str = "local bend = require('bend')\n\
        local ann = troupe.actor{ name = 'ann' }\n\
        ann:play(troupe.sequence{ name = 'lift', r_elbow_flexion = { {0, 0}, {1, bend} } })\n";

    #[test]
    fn an_edit_reloads_the_scene_at_the_same_time_as_a_fresh_run() {
        let dir = folder("edit");
        let scene = dir.join("scene.lua");
        let module = dir.join("bend.lua");
        write(&scene, SCENE);
        write(&module, "return 1.0\n");
        let (mut reloader, mut session) = Reloader::start(scene.clone(), make).unwrap();
        assert_eq!(reloader.files(), vec![scene.clone(), module.clone()]);
        session
            .run(RunLimit {
                ticks: 50,
                until_idle: false,
            })
            .unwrap();
        assert!(!reloader.changed());

        // An edit of a module the scene required: reloaded at tick 50.
        write(&module, "return 2.0\n");
        assert!(reloader.changed());
        let reloaded = reloader.reload(&session).expect("reloads");
        assert_eq!(reloaded.scene().tick(), 50);
        assert!(reloader.error().is_none());
        assert!(!reloader.changed());
        // The same as a fresh run of the edited scene to that time, bit for bit.
        let (_, mut fresh) = Reloader::start(scene.clone(), make).unwrap();
        fresh
            .run(RunLimit {
                ticks: 50,
                until_idle: false,
            })
            .unwrap();
        assert_eq!(elbow(&reloaded).to_bits(), elbow(&fresh).to_bits());
        assert!(
            (elbow(&reloaded) - 2.0 * elbow(&session)).abs() < 1e-9,
            "the new bend"
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_broken_edit_keeps_the_last_good_scene_and_shows_the_error() {
        let dir = folder("broken");
        let scene = dir.join("scene.lua");
        write(&scene, "local ann = troupe.actor{ name = 'ann' }\n");
        write(&dir.join("bend.lua"), "return 1.0\n");
        let (mut reloader, mut session) = Reloader::start(scene.clone(), make).unwrap();
        session
            .run(RunLimit {
                ticks: 10,
                until_idle: false,
            })
            .unwrap();

        write(&scene, "local ann = troupe.actor{ name = 'ann' \n");
        assert!(
            reloader.reload(&session).is_none(),
            "a syntax error does not reload"
        );
        let error = reloader.error().expect("the error is kept").to_string();
        assert!(error.contains("scene.lua:"), "{error}");
        assert!(!reloader.changed(), "not retried until the next edit");
        let frame = reloader.frame(&session);
        assert_eq!(frame.actors.len(), 1, "the last good scene");
        assert!(frame.notice[0].contains("reload of"), "{:?}", frame.notice);
        assert!(
            frame.notice.iter().any(|l| l.contains("scene.lua:")),
            "{:?}",
            frame.notice
        );
        // The notice is drawn: a red panel in the top-left corner.
        let mut renderer = troupe_viewer::OffscreenRenderer::new(320, 200).unwrap();
        let camera = troupe_viewer::Camera::fit();
        let picture = renderer.render(&frame, &camera).unwrap();
        let px = picture.get_pixel(2, 4).0;
        let redness = |px: [u8; 4]| px[0] as i32 - px[1] as i32;
        assert!(redness(px) > 50, "red panel, got {px:?}");
        let plain = renderer.render(&troupe_viewer::Frame::from_scene(session.scene()), &camera);
        let px = plain.unwrap().get_pixel(2, 4).0;
        assert!(redness(px) < 20, "no panel without a notice, got {px:?}");

        // Fixed: reloads, and the error goes.
        write(&scene, SCENE);
        let fixed = reloader.reload(&session).expect("reloads once fixed");
        assert_eq!(fixed.scene().tick(), 10);
        assert!(reloader.error().is_none());
        assert!(reloader.frame(&fixed).notice.is_empty());
        std::fs::remove_dir_all(&dir).ok();
    }
}
