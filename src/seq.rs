//! `troupe seq`: inspect, convert and edit motion sequences (thesis chapter 5) in `.trk`
//! and BVH files, and plot their curves.
//!
//! A BVH input becomes a sequence of its own channels (`JOINT.Xrotation` in radians,
//! `JOINT.Xposition` times `--scale`, metres); a `.bvh` output is written on the first BVH
//! input's hierarchy. `.trk` files are read and written as they are.

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;
use troupe_formats::bvh::{read_bvh, write_bvh, Bvh, RotationOrder};
use troupe_formats::retarget::{bvh_axes, map_for, retarget, RetargetMap};
use troupe_formats::trk::read_trk_file;
use troupe_formats::{
    load_sequence, load_sequences, save_recording, save_rig, save_sequences, Format, Rig,
};
use troupe_motion::offline::compress::{compress_pyramid, compress_spline, SplineOptions};
use troupe_motion::offline::pyramid::{self, Grid};
use troupe_motion::offline::warp::{squeeze_stretch, warp_sequence, TimeWarp};
use troupe_motion::{offline::blend as seqblend, Sequence};

/// Options of `troupe seq`.
#[derive(Args)]
pub struct SeqArgs {
    /// Length unit of BVH files in metres (0.01 for centimetres, 0.0254 for inches).
    #[arg(long, global = true, default_value_t = 0.01)]
    scale: f64,
    /// The actor to work on in a .trk recording of several (`troupe run --record`): its
    /// sequence alone. Without it `seq convert` writes every actor, and the other
    /// commands take the first, saying so.
    #[arg(long, global = true, value_name = "NAME")]
    actor: Option<String>,
    #[command(subcommand)]
    command: SeqCommand,
}

#[derive(Subcommand)]
enum SeqCommand {
    /// Joints, DOFs, frames and rate of a file; with --positions, global joint positions.
    Info {
        /// A .bvh or .trk file.
        file: PathBuf,
        /// Frame whose positions to print.
        #[arg(long, default_value_t = 0)]
        frame: usize,
        /// Print the global joint positions at --frame (BVH: file units; troupe: metres).
        #[arg(long)]
        positions: bool,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Converts between .bvh, .trk, .gltf and .glb (BVH rotation order chosen on output).
    Convert {
        /// Input .bvh or .trk (or, with --template, a .gltf/.glb written by troupe).
        input: PathBuf,
        /// Output .bvh, .trk, .gltf or .glb.
        output: PathBuf,
        /// Rotation order written to a BVH output (e.g. ZXY); default: as read.
        #[arg(long)]
        rotation_order: Option<String>,
        /// Play the input on this body template (e.g. `adult`): a BVH is retargeted onto it
        /// (read back exactly if it is troupe's own hierarchy), a .trk or glTF played on it;
        /// the output may then be .trk, .bvh (on the template's hierarchy) or glTF.
        #[arg(long)]
        template: Option<String>,
        /// Standing height in metres of the --template body (default: the one a .trk
        /// records for that template, else the template's); a BVH's root translation is
        /// scaled to it, so its feet stay on the floor.
        #[arg(long, value_name = "METRES", requires = "template")]
        height: Option<f64>,
        /// A retargeting map file (`BVH_JOINT TROUPE_JOINT` per line); default: the
        /// `.map` beside the BVH, else detect CMU or Mixamo names. Without --template, a
        /// BVH written to glTF is turned upright by the axes it gives. BVH input only, with
        /// --template or to glTF.
        #[arg(long)]
        map: Option<PathBuf>,
    },
    /// Blends B into A: B starts at --at, the weight eases over --over seconds (eq. 5-8),
    /// or the multiresolution blend of table 5-5 with --pyramid LEVELS.
    Blend {
        /// First sequence.
        a: PathBuf,
        /// Second sequence.
        b: PathBuf,
        /// Output file.
        output: PathBuf,
        /// Time of A where B starts (seconds).
        #[arg(long)]
        at: f64,
        /// Transition length (seconds).
        #[arg(long)]
        over: f64,
        /// Blend on a Laplacian pyramid of this many levels.
        #[arg(long)]
        pyramid: Option<usize>,
    },
    /// Reduces the keys within a tolerance (radians or metres) at every original key.
    Compress {
        /// Input file.
        input: PathBuf,
        /// Output file.
        output: PathBuf,
        /// Largest allowed error at any original key.
        #[arg(long)]
        tolerance: f64,
        /// Spline (thesis 5.8) or pyramid (5.5) compression.
        #[arg(long, value_enum, default_value_t = Method::Spline)]
        method: Method,
    },
    /// Time warping from original:new time pairs, e.g. --map 0:0,1:1.5,2:2.2, or
    /// squeeze/stretch around one key time with --squeeze TL:T:TR:NEW (thesis 5.6).
    Warp {
        /// Input file.
        input: PathBuf,
        /// Output file.
        output: PathBuf,
        /// Comma-separated `t:t'` pairs, increasing in both.
        #[arg(long, required_unless_present = "squeeze")]
        map: Option<String>,
        /// Move key time T to NEW inside [TL, TR], keeping the ratios on both sides.
        #[arg(long, conflicts_with = "map")]
        squeeze: Option<String>,
    },
    /// Band editing (eq. 5-9): weights w0 (finest band) … wN-1, then the top level; what
    /// the weights change is added to the keys, so all ones give the motion back.
    Bands {
        /// Input file.
        input: PathBuf,
        /// Output file.
        output: PathBuf,
        /// Comma-separated weights; their count minus one is the number of levels.
        #[arg(long)]
        weights: String,
    },
    /// Plots DOF curves over time into a PNG, keys marked (the curve viewer of 6.2).
    Plot {
        /// Input file.
        input: PathBuf,
        /// Output .png.
        output: PathBuf,
        /// Comma-separated DOF (track) names; default: the first four tracks.
        #[arg(long, value_delimiter = ',')]
        dofs: Vec<String>,
        /// Also draw the Gaussian pyramid levels G1…GN of each curve.
        #[arg(long)]
        pyramid: Option<usize>,
        /// Image width in pixels, 200 to 8000.
        #[arg(long, default_value_t = 1200, value_parser = clap::value_parser!(u32).range(200..=8000))]
        width: u32,
    },
}

/// The compression methods of `seq compress`.
#[derive(Clone, Copy, ValueEnum)]
enum Method {
    /// Spline compression (5.8).
    Spline,
    /// Pyramid compression (5.5).
    Pyramid,
}

/// A loaded input: its sequence and, for BVH files, the motion (to write BVH back).
struct Loaded {
    seq: Sequence,
    bvh: Option<Bvh>,
}

/// Loads the sequence of an input: a BVH as its own channels (keeping the motion, to write
/// BVH back); any other file through the dispatch (of a `.trk` recording several actors,
/// `actor`'s sequence, else the first).
fn load(path: &Path, scale: f64, actor: Option<&str>) -> Result<Loaded> {
    if Format::of(path)? == Format::Bvh {
        if let Some(name) = actor {
            bail!(
                "--actor {name}: {} is a BVH file, which holds one motion (--actor picks an \
                 actor of a .trk recording)",
                path.display()
            );
        }
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let bvh = read_bvh(path)?;
        let mut seq = bvh.to_channel_sequence(&name, scale)?;
        seq.meta.insert("source".into(), path.display().to_string());
        return Ok(Loaded {
            seq,
            bvh: Some(bvh),
        });
    }
    if Format::of(path)?.binds_to_body() {
        bail!(
            "{}: glTF input needs --template (the body to read it onto)",
            path.display()
        );
    }
    let mut set = load_sequences(path, None)?;
    let seq = match actor {
        // Asked for by name, the actor must be there, one or many (a recording of `a`
        // read for `--actor bob` went on with `a`, saying nothing).
        Some(name) => pick(path, set, name)?,
        _ if set.is_empty() => bail!("{}: the file holds no sequence", path.display()),
        _ => {
            if set.len() > 1 {
                tracing::warn!(
                    "{}: {} actors ({}); using the first, `{}` (choose one with --actor NAME)",
                    path.display(),
                    set.len(),
                    actor_names(&set),
                    set[0].name
                );
            }
            set.remove(0)
        }
    };
    Ok(Loaded { seq, bvh: None })
}

/// The sequence of `actor` in `set` (read from `path`), or an error naming those there are.
fn pick(path: &Path, set: Vec<Sequence>, actor: &str) -> Result<Sequence> {
    let names = actor_names(&set);
    set.into_iter().find(|s| s.name == actor).with_context(|| {
        format!(
            "--actor {actor}: {} has no actor `{actor}` (actors: {names})",
            path.display()
        )
    })
}

/// The names of a recording's sequences (its actors), comma-separated.
fn actor_names(set: &[Sequence]) -> String {
    let names: Vec<&str> = set.iter().map(|s| s.name.as_str()).collect();
    names.join(", ")
}

/// Up to eight of `names`, comma-separated, then how many more there are.
fn some_names(names: &[&str]) -> String {
    let shown = names.len().min(8);
    let mut text = names[..shown].join(", ");
    if names.len() > shown {
        text += &format!(" and {} more", names.len() - shown);
    }
    text
}

/// Refuses a blend of sequences that share no track (of different skeletons: nothing to
/// blend), and warns of the tracks only one of them has: the blend keeps those as that
/// one plays them, unblended.
fn check_blend(a: (&Path, &Sequence), b: (&Path, &Sequence)) -> Result<()> {
    let only = |x: &Sequence, y: &Sequence| -> Vec<String> {
        let lacking = x.tracks().iter().filter(|t| y.track(t.dof()).is_none());
        lacking.map(|t| t.dof().to_string()).collect()
    };
    let (only_a, only_b) = (only(a.1, b.1), only(b.1, a.1));
    if only_a.len() == a.1.tracks().len() {
        bail!(
            "{} and {} share no track: nothing to blend (sequences of different skeletons?)",
            a.0.display(),
            b.0.display()
        );
    }
    for ((path, _), only) in [(a, only_a), (b, only_b)] {
        if !only.is_empty() {
            let names: Vec<&str> = only.iter().map(String::as_str).collect();
            tracing::warn!(
                "{}: {} track(s) the other sequence lacks, kept unblended: {}",
                path.display(),
                only.len(),
                some_names(&names)
            );
        }
    }
    Ok(())
}

/// Saves an edited sequence: to BVH on the hierarchy of the BVH input it came from,
/// otherwise through the dispatch (a `.trk`).
fn save(path: &Path, seq: &Sequence, template: Option<&Bvh>, scale: f64) -> Result<()> {
    if Format::of(path)? == Format::Bvh {
        let Some(b) = template else {
            bail!(
                "{}: writing BVH needs a BVH input (its hierarchy)",
                path.display()
            );
        };
        // A track without a channel on the hierarchy would vanish from the file (a blend
        // with another skeleton's motion): refused rather than dropped.
        let channels: std::collections::HashSet<String> = b
            .joints()
            .iter()
            .flat_map(|j| j.channels.iter().map(move |c| format!("{}.{c}", j.name)))
            .collect();
        let lost: Vec<&str> = seq
            .tracks()
            .iter()
            .map(|t| t.dof())
            .filter(|d| !channels.contains(*d))
            .collect();
        if !lost.is_empty() {
            bail!(
                "{}: the BVH hierarchy written has no channel for {} track(s): {}; write a .trk to keep them",
                path.display(),
                lost.len(),
                some_names(&lost)
            );
        }
        let scale = seq
            .meta
            .get("bvh_scale")
            .and_then(|s| s.parse().ok())
            .unwrap_or(scale);
        write_bvh(path, &b.with_channel_sequence(seq, scale)?)?;
    } else {
        save_sequences(path, std::slice::from_ref(seq), [])?;
    }
    Ok(())
}

fn key_count(seq: &Sequence) -> usize {
    seq.tracks().iter().map(|t| t.keys().len()).sum()
}

fn parse_list(s: &str) -> Result<Vec<f64>> {
    s.split(',')
        .map(|x| {
            x.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .with_context(|| format!("`{x}` is not a number"))
        })
        .collect()
}

/// Runs a `troupe seq` command.
pub fn run(args: SeqArgs) -> Result<ExitCode> {
    let scale = args.scale;
    let actor = args.actor.as_deref();
    if !(scale.is_finite() && scale > 0.0) {
        bail!("--scale must be a positive number of metres per BVH unit");
    }
    match args.command {
        SeqCommand::Info {
            file,
            frame,
            positions,
            json,
        } => info(&file, frame, positions, json, scale)?,
        SeqCommand::Convert {
            input,
            output,
            rotation_order,
            template,
            height,
            map,
        } => convert(
            &input,
            &output,
            rotation_order,
            (template, height),
            map,
            (scale, actor),
        )?,
        SeqCommand::Blend {
            a,
            b,
            output,
            at,
            over,
            pyramid: levels,
        } => {
            let (la, lb) = (load(&a, scale, actor)?, load(&b, scale, actor)?);
            check_blend((&a, &la.seq), (&b, &lb.seq))?;
            let start = Instant::now();
            let s = match levels {
                Some(n) => {
                    pyramid::pyramid_blend(&la.seq, &lb.seq, at, over, n, pyramid::DEFAULT_A)?
                }
                None => seqblend::blend(&la.seq, &lb.seq, at, over, None)?,
            };
            let took = start.elapsed();
            save(&output, &s, la.bvh.as_ref().or(lb.bvh.as_ref()), scale)?;
            println!(
                "blended {} tracks over [{:.3}, {:.3}] s in {:.1} ms -> {}",
                s.tracks().len(),
                s.start(),
                s.end(),
                took.as_secs_f64() * 1e3,
                output.display()
            );
        }
        SeqCommand::Compress {
            input,
            output,
            tolerance,
            method,
        } => {
            let l = load(&input, scale, actor)?;
            let start = Instant::now();
            let (s, r) = match method {
                Method::Spline => compress_spline(&l.seq, &SplineOptions::new(tolerance))?,
                Method::Pyramid => compress_pyramid(&l.seq, tolerance, pyramid::DEFAULT_A)?,
            };
            let took = start.elapsed();
            save(&output, &s, l.bvh.as_ref(), scale)?;
            println!(
                "keys before: {}\nkeys after:  {} ({:.1} %)\nmax error:   {:.3e} (tolerance {tolerance:e})\ntime:        {:.1} ms",
                r.keys_before,
                r.keys_after,
                100.0 * r.keys_after as f64 / r.keys_before.max(1) as f64,
                r.max_error,
                took.as_secs_f64() * 1e3
            );
        }
        SeqCommand::Warp {
            input,
            output,
            map,
            squeeze,
        } => {
            let l = load(&input, scale, actor)?;
            let s = if let Some(sq) = squeeze {
                let v: Vec<f64> = sq
                    .split(':')
                    .map(|x| parse_list(x).map(|v| v[0]))
                    .collect::<Result<_>>()?;
                let [tl, t, tr, new] = v[..] else {
                    bail!("--squeeze needs TL:T:TR:NEW");
                };
                squeeze_stretch(&l.seq, tl, t, tr, new)?
            } else {
                let pairs = map
                    .unwrap_or_default()
                    .split(',')
                    .map(|p| {
                        let (a, b) = p
                            .split_once(':')
                            .with_context(|| format!("`{p}` is not t:t'"))?;
                        Ok((parse_list(a)?[0], parse_list(b)?[0]))
                    })
                    .collect::<Result<Vec<_>>>()?;
                warp_sequence(&l.seq, &TimeWarp::new(&pairs)?)?
            };
            save(&output, &s, l.bvh.as_ref(), scale)?;
            println!(
                "warped [{:.3}, {:.3}] s to [{:.3}, {:.3}] s -> {}",
                l.seq.start(),
                l.seq.end(),
                s.start(),
                s.end(),
                output.display()
            );
            // The warp keeps `meta rate` true (see `remap_times`): say what became of it.
            match (l.seq.meta.get("rate"), s.meta.get("rate")) {
                (Some(from), Some(to)) if from != to => println!("rate {from} Hz -> {to} Hz"),
                (Some(from), None) => println!(
                    "rate {from} Hz dropped: the warp spaced the keys unevenly (BVH and glTF \
                     output sample every {:.4} s)",
                    s.frame_time()
                ),
                _ => {}
            }
        }
        SeqCommand::Bands {
            input,
            output,
            weights,
        } => {
            let w = parse_list(&weights)?;
            let l = load(&input, scale, actor)?;
            let s = pyramid::band_edit(&l.seq, &w, pyramid::DEFAULT_A)?;
            save(&output, &s, l.bvh.as_ref(), scale)?;
            println!(
                "band-edited {} tracks with {} levels -> {}",
                s.tracks().len(),
                w.len() - 1,
                output.display()
            );
        }
        SeqCommand::Plot {
            input,
            output,
            dofs,
            pyramid: levels,
            width,
        } => {
            let l = load(&input, scale, actor)?;
            plot(&l.seq, &output, &dofs, levels, width)?;
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn convert(
    input: &Path,
    output: &Path,
    rotation_order: Option<String>,
    (template, height): (Option<String>, Option<f64>),
    map: Option<PathBuf>,
    (scale, actor): (f64, Option<&str>),
) -> Result<()> {
    let order = rotation_order
        .map(|o| o.parse::<RotationOrder>())
        .transpose()?;
    let name = input
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let input_format = Format::of(input)?;
    let output_format = Format::of(output)?;
    let gltf_out = matches!(output_format, Format::Gltf | Format::Glb);
    // A retargeting map names BVH joints: on another input it would mean nothing.
    if let Some(m) = &map {
        if input_format != Format::Bvh {
            bail!(
                "--map {}: a retargeting map applies to a BVH input, and {} is a {} file",
                m.display(),
                input.display(),
                input_format.name()
            );
        }
        // It retargets onto a template, or gives the axes of a BVH written to glTF; any
        // other conversion of a BVH would not read it.
        if template.is_none() && !gltf_out {
            bail!(
                "--map {}: a retargeting map is read with --template, or for a BVH written \
                 to glTF; converting {} to {} it would be ignored",
                m.display(),
                input.display(),
                output.display()
            );
        }
    }
    if input_format == Format::Trk {
        if order.is_some() {
            bail!("--rotation-order applies to BVH → BVH conversion");
        }
        return convert_trk(input, output, (template, height), actor);
    }
    if let Some(t) = template {
        let t = troupe_body::template(&t)?;
        // A glTF file troupe wrote keeps its body's offsets: that body is kept unless
        // --height says otherwise (on another template, the glTF's root is scaled to it).
        let recorded = match input_format {
            Format::Gltf | Format::Glb => troupe_formats::gltf::recorded_body(input)?
                .filter(|(name, _)| name == t.name)
                .map(|(_, h)| h),
            _ => None,
        };
        let mut params = t.default_params();
        if let Some(h) = height.or(recorded) {
            params.height = h;
        }
        let skeleton = t.instantiate(params)?;
        let mut seq = match map {
            Some(m) => retarget(&skeleton, &read_bvh(input)?, &RetargetMap::read(m)?, &name)
                .with_context(|| format!("retargeting {}", input.display()))?,
            _ => load_sequence(input, Some(&skeleton))?,
        };
        if let Some(map) = seq.meta.get("retarget_map") {
            println!("retargeting with the `{map}` map");
        }
        // The body the output was made for: `troupe view` of a .trk shows that body.
        seq.meta.insert("template".into(), t.name.into());
        seq.meta.insert("height".into(), params.height.to_string());
        save_sequences(
            output,
            std::slice::from_ref(&seq),
            [(name.as_str(), &skeleton)],
        )?;
    } else if input_format == Format::Bvh && (output_format == Format::Bvh || gltf_out) {
        let mut b = read_bvh(input)?;
        if let Some(o) = order {
            b = b.with_rotation_order(o);
        }
        if gltf_out {
            let mut rig = Rig::from_bvh(&b, scale);
            // glTF is Y up and faces +Z: a file of other axes (a Z-up one) is turned as
            // retargeting would turn it, so that the figure stands in a glTF viewer.
            let map = match &map {
                Some(m) => RetargetMap::read(m)?,
                None => map_for(input, &b)?,
            };
            match bvh_axes(&b, &map) {
                Ok(axes) if !axes.is_troupes() => {
                    rig.turn(axes.turn);
                    println!(
                        "turned to glTF's axes: the file's up {} and forward {} became +Y and +Z",
                        axes.up, axes.forward
                    );
                }
                Ok(_) => {}
                Err(e) => println!("kept the file's axes: cannot tell which way is up ({e})"),
            }
            save_rig(output, &rig, &name, b.frame_time())?;
        } else {
            write_bvh(output, &b)?;
        }
    } else {
        if order.is_some() {
            bail!("--rotation-order applies to BVH → BVH conversion");
        }
        let l = load(input, scale, actor)?;
        save(output, &l.seq, l.bvh.as_ref(), scale)?;
    }
    println!("wrote {}", output.display());
    Ok(())
}

/// `seq convert` of a `.trk`: every actor it records (`actor`'s alone if given) and its
/// objects, to a `.trk`, or played on `--template` to BVH or glTF — one file per actor,
/// `NAME.ACTOR.EXT`, when there are several, as `troupe run --record` writes them.
fn convert_trk(
    input: &Path,
    output: &Path,
    (template, height): (Option<String>, Option<f64>),
    actor: Option<&str>,
) -> Result<()> {
    let file = read_trk_file(input)?;
    let mut sequences = match actor {
        Some(name) => vec![pick(input, file.sequences, name)?],
        None => file.sequences,
    };
    let output_format = Format::of(output)?;
    let written = match template {
        None if output_format != Format::Trk => bail!(
            "{} output of a .trk needs --template (the body to play it on)",
            output_format.name()
        ),
        None => save_recording(output, &sequences, &file.objects, [])?,
        Some(t) => {
            let t = troupe_body::template(&t)?;
            let mut skeletons = Vec::new();
            for seq in &mut sequences {
                // An actor recorded on this template keeps its height, unless --height
                // says otherwise.
                let recorded = seq
                    .meta
                    .get("height")
                    .filter(|_| seq.meta.get("template").is_some_and(|n| n == t.name))
                    .and_then(|h| h.parse::<f64>().ok());
                let mut params = t.default_params();
                if let Some(h) = height.or(recorded) {
                    params.height = h;
                }
                skeletons.push(t.instantiate(params)?);
                // The body the output was made for: `troupe view` of a .trk shows it.
                seq.meta.insert("template".into(), t.name.into());
                seq.meta.insert("height".into(), params.height.to_string());
            }
            let names: Vec<String> = sequences.iter().map(|s| s.name.clone()).collect();
            let actors = names.iter().map(String::as_str).zip(&skeletons);
            save_recording(output, &sequences, &file.objects, actors)?
        }
    };
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn info(file: &Path, frame: usize, positions: bool, as_json: bool, scale: f64) -> Result<()> {
    let format = Format::of(file)?;
    if format.binds_to_body() && format != Format::Bvh {
        bail!("{}: `seq info` reads .bvh and .trk files", file.display());
    }
    if format == Format::Bvh {
        let b = read_bvh(file)?;
        let joints: Vec<_> = b
            .joints()
            .iter()
            .map(|j| {
                json!({
                    "name": j.name,
                    "parent": j.parent.map(|p| b.joints()[p].name.clone()),
                    "offset": [j.offset.x, j.offset.y, j.offset.z],
                    "channels": j.channels.iter().map(|c| c.to_string()).collect::<Vec<_>>(),
                    "end_sites": j.end_sites.len(),
                })
            })
            .collect();
        let pos = if positions {
            if frame >= b.frame_count() {
                bail!("--frame {frame}: the file has {} frames", b.frame_count());
            }
            Some(
                b.joint_positions(frame)
                    .iter()
                    .zip(b.joints())
                    .map(|(p, j)| (j.name.clone(), [p.x, p.y, p.z]))
                    .collect::<Vec<_>>(),
            )
        } else {
            None
        };
        if as_json {
            let mut v = json!({
                "file": file.display().to_string(),
                "format": "bvh",
                "joints": joints,
                "channels": b.channel_count(),
                "frames": b.frame_count(),
                "frame_time": b.frame_time(),
                "rate": 1.0 / b.frame_time(),
                "duration": b.duration(),
            });
            if let Some(p) = &pos {
                v["frame"] = json!(frame);
                v["positions"] = json!(p
                    .iter()
                    .map(|(n, x)| json!({"joint": n, "position": x}))
                    .collect::<Vec<_>>());
            }
            println!("{}", serde_json::to_string_pretty(&v)?);
        } else {
            println!(
                "{}: BVH, {} joints, {} channels (DOFs), {} frames at {:.3} Hz ({:.3} s)",
                file.display(),
                b.joints().len(),
                b.channel_count(),
                b.frame_count(),
                1.0 / b.frame_time(),
                b.duration()
            );
            for j in b.joints() {
                let depth = std::iter::successors(j.parent, |&p| b.joints()[p].parent).count();
                let ch: Vec<String> = j.channels.iter().map(|c| c.to_string()).collect();
                println!("  {}{} [{}]", "  ".repeat(depth), j.name, ch.join(" "));
            }
            if let Some(p) = pos {
                println!(
                    "global joint positions at frame {frame} (file units; ×{scale} for metres):"
                );
                for (n, x) in p {
                    println!("  {n:<24} {:>12.6} {:>12.6} {:>12.6}", x[0], x[1], x[2]);
                }
            }
        }
    } else {
        let set = load_sequences(file, None)?;
        if positions {
            bail!("--positions needs a BVH file (a .trk has no hierarchy)");
        }
        let seqs: Vec<_> = set
            .iter()
            .map(|s| {
                json!({
                    "name": s.name,
                    "looping": s.looping,
                    "meta": s.meta,
                    "start": s.start(),
                    "duration": s.duration(),
                    "rate": 1.0 / s.frame_time(),
                    "tracks": s.tracks().iter().map(|t| json!({"dof": t.dof(), "keys": t.keys().len(), "interpolation": t.interpolation().name()})).collect::<Vec<_>>(),
                })
            })
            .collect();
        if as_json {
            let v = json!({"file": file.display().to_string(), "format": "trk", "sequences": seqs});
            println!("{}", serde_json::to_string_pretty(&v)?);
        } else {
            for s in &set {
                println!(
                    "{}: sequence `{}`, {} tracks (DOFs), {} keys, [{:.3}, {:.3}] s, rate {:.3} Hz{}",
                    file.display(),
                    s.name,
                    s.tracks().len(),
                    key_count(s),
                    s.start(),
                    s.end(),
                    1.0 / s.frame_time(),
                    if s.looping { ", loops" } else { "" }
                );
                for (k, v) in &s.meta {
                    println!("  meta {k} {v}");
                }
                for t in s.tracks() {
                    println!(
                        "  {:<32} {:>6} keys, {}",
                        t.dof(),
                        t.keys().len(),
                        t.interpolation().name()
                    );
                }
            }
        }
    }
    Ok(())
}

/// Colours of the curves, in order.
const COLOURS: [[u8; 3]; 8] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [255, 127, 14],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [23, 190, 207],
];

fn plot(
    seq: &Sequence,
    output: &Path,
    dofs: &[String],
    levels: Option<usize>,
    width: u32,
) -> Result<()> {
    let tracks: Vec<_> = if dofs.is_empty() {
        seq.tracks().iter().take(4).collect()
    } else {
        dofs.iter()
            .map(|d| seq.track(d).with_context(|| format!("no track `{d}`")))
            .collect::<Result<_>>()?
    };
    if tracks.is_empty() {
        bail!("nothing to plot");
    }
    let panel = 240u32;
    let height = panel * tracks.len() as u32;
    let mut img = image::RgbImage::from_pixel(width, height, image::Rgb([255, 255, 255]));
    let (t0, t1) = (seq.start(), seq.end().max(seq.start() + 1e-9));
    let margin = 30.0;
    for (p, track) in tracks.iter().enumerate() {
        let top = p as f64 * panel as f64;
        let samples = (width as usize).max(2);
        let dt = (t1 - t0) / (samples - 1) as f64;
        let mut curves: Vec<(Vec<f64>, f64, f64)> = vec![(track.sample(t0, dt, samples), t0, dt)];
        if let Some(n) = levels {
            let grid = Grid::covering(t0, t1, seq.frame_time(), n)?;
            let g = pyramid::gaussian(
                &track.sample(grid.start, grid.dt, grid.n),
                n,
                pyramid::DEFAULT_A,
            )?;
            for (l, level) in g.into_iter().enumerate().skip(1) {
                curves.push((level, grid.start, grid.dt * (1u64 << l) as f64));
            }
        }
        let (lo, hi) = curves
            .iter()
            .flat_map(|c| c.0.iter())
            .chain(track.keys().iter().map(|k| &k.value))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let span = if hi - lo > 1e-12 { hi - lo } else { 1.0 };
        let x = |t: f64| margin + (t - t0) / (t1 - t0) * (width as f64 - 2.0 * margin);
        let y =
            |v: f64| top + panel as f64 - margin - (v - lo) / span * (panel as f64 - 2.0 * margin);
        // Frame: axes and the zero line when in range.
        let grey = [170, 170, 170];
        line(&mut img, x(t0), y(lo), x(t1), y(lo), grey);
        line(&mut img, x(t0), y(lo), x(t0), y(hi), grey);
        if lo < 0.0 && hi > 0.0 {
            line(&mut img, x(t0), y(0.0), x(t1), y(0.0), [225, 225, 225]);
        }
        for (c, (values, start, step)) in curves.iter().enumerate().rev() {
            let colour = COLOURS[(p + c) % COLOURS.len()];
            let colour = if c == 0 {
                colour
            } else {
                [120 + 20 * c as u8 % 100, 120, 120]
            };
            for i in 1..values.len() {
                let (ta, tb) = (start + (i - 1) as f64 * step, start + i as f64 * step);
                line(
                    &mut img,
                    x(ta),
                    y(values[i - 1]),
                    x(tb),
                    y(values[i]),
                    colour,
                );
            }
        }
        for k in track.keys() {
            let (cx, cy) = (x(k.time).round() as i64, y(k.value).round() as i64);
            for dx in -2..=2 {
                for dy in -2..=2 {
                    put(&mut img, cx + dx, cy + dy, [0, 0, 0]);
                }
            }
        }
        println!(
            "panel {}: {} ({} keys), values [{lo:.4}, {hi:.4}], time [{t0:.3}, {t1:.3}] s{}",
            p + 1,
            track.dof(),
            track.keys().len(),
            if levels.is_some() {
                ", grey: Gaussian levels G1…GN"
            } else {
                ""
            }
        );
    }
    img.save(output)
        .with_context(|| format!("writing {}", output.display()))?;
    println!("wrote {}", output.display());
    Ok(())
}

fn put(img: &mut image::RgbImage, x: i64, y: i64, c: [u8; 3]) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, image::Rgb(c));
    }
}

/// Draws a line by stepping along its longer axis.
fn line(img: &mut image::RgbImage, x0: f64, y0: f64, x1: f64, y1: f64, c: [u8; 3]) {
    let steps = (x1 - x0).abs().max((y1 - y0).abs()).ceil().max(1.0) as i64;
    for s in 0..=steps.min(100_000) {
        let f = s as f64 / steps as f64;
        put(
            img,
            (x0 + f * (x1 - x0)).round() as i64,
            (y0 + f * (y1 - y0)).round() as i64,
            c,
        );
    }
}
