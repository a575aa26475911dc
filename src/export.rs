//! `troupe export urdf OUT.urdf`: a body template as URDF, for dynamics and robotics tools
//! (the writer and its conventions are [`troupe_formats::urdf`]); `troupe export gltf
//! OUT.glb`: a body template as a skinned glTF character (its generated skin bound to its
//! joints), or a user's character (`--look FILE`) fitted to it.

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use troupe_body::TemplateParams;

/// Options of `troupe export`.
#[derive(Args)]
pub struct ExportArgs {
    #[command(subcommand)]
    format: Format,
}

#[derive(Subcommand)]
enum Format {
    /// Write a body template as a URDF robot description (Z up).
    Urdf(UrdfArgs),
    /// Write a body template as a skinned glTF character (.gltf + .bin, or .glb), or a
    /// user's character fitted to it (--look).
    Gltf(GltfArgs),
}

/// Options of `troupe export gltf`.
#[derive(Args)]
struct GltfArgs {
    /// The file to write (.gltf or .glb).
    out: PathBuf,
    /// Body template.
    #[arg(long, default_value = "adult")]
    template: String,
    /// Standing height in metres (default: the template's).
    #[arg(long)]
    height: Option<f64>,
    /// Body mass in kilograms (default: the template's).
    #[arg(long)]
    mass: Option<f64>,
    /// Write this user's character (.glb, .gltf or .vrm) as troupe fits it to the body,
    /// instead of troupe's generated skin (as Lua's `troupe.actor{ look = FILE }`).
    #[arg(long, value_name = "FILE")]
    look: Option<PathBuf>,
    /// Bones of the --look file for troupe's joints, as Lua's `bones` map: KEY=NODE, KEY
    /// a VRM humanoid bone or troupe joint name, NODE the file's node (repeat, or
    /// separate with commas).
    #[arg(long, value_name = "KEY=NODE", value_delimiter = ',', requires = "look", value_parser = bone_pair)]
    bones: Vec<(String, String)>,
    /// The --look character's pose: `rest`, troupe's rest posture (a one-frame
    /// animation); `bind`, the file's own bind pose (no animation).
    #[arg(long, value_enum, default_value_t = Pose::Rest, requires = "look")]
    pose: Pose,
}

/// The pose `troupe export gltf --look` writes a user's character in.
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
enum Pose {
    /// troupe's rest posture.
    Rest,
    /// the character file's bind pose.
    Bind,
}

/// A `--bones` pair, `KEY=NODE`.
fn bone_pair(text: &str) -> Result<(String, String), String> {
    match text.split_once('=') {
        Some((key, node)) if !key.trim().is_empty() && !node.trim().is_empty() => {
            Ok((key.trim().to_string(), node.trim().to_string()))
        }
        _ => Err(format!(
            "`{text}` is not KEY=NODE (hips=Skeleton_torso_joint_1)"
        )),
    }
}

/// Writes the skinned character of `a` at rest: troupe's generated skin, or the
/// user's `--look` character fitted to the body.
fn export_gltf(a: GltfArgs) -> Result<ExitCode> {
    let t = troupe_body::template(&a.template)?;
    let d = t.default_params();
    let height = a.height.unwrap_or(d.height);
    let skeleton = t.instantiate(TemplateParams {
        height,
        mass: a.mass.unwrap_or(d.mass),
    })?;
    let rest = troupe_motion::sequence::Sequence::new("rest");
    let mut rig = troupe_formats::Rig::from_sequence(&skeleton, &rest)?;
    if let Some(look) = &a.look {
        let character = troupe_formats::character::read_character(look, &a.bones)?;
        let dressing = character.dress(&skeleton, height)?;
        if a.pose == Pose::Bind {
            // No frames: the nodes keep their rest transforms, the bind pose.
            rig.times.clear();
            rig.rotations.clear();
            rig.translations.clear();
        }
        troupe_formats::save_character(&a.out, &dressing, &rig, &a.template)
            .with_context(|| format!("writing {}", a.out.display()))?;
        eprintln!(
            "wrote {} ({} on the {}: {} bones, {} vertices, {} triangles)",
            a.out.display(),
            look.display(),
            a.template,
            dressing.bone_names.len(),
            dressing.positions.len(),
            dressing.indices.len() / 3
        );
        return Ok(ExitCode::SUCCESS);
    }
    // Every height of a template shares one skin, scaled (as in the viewer and in
    // recordings).
    let skin = troupe_body::skin::SkinLibrary::default()
        .get(&skeleton)?
        .to_skin();
    troupe_formats::save_skinned(&a.out, &rig, Some(&skin), &a.template)
        .with_context(|| format!("writing {}", a.out.display()))?;
    // The file holds the skin cut along the edges between its regions (see
    // `troupe_body::skin::CutSkin`): count what it holds.
    let written = troupe_body::skin::CutSkin::new(&skin);
    eprintln!(
        "wrote {} ({} joints and {} helper joints, a skin of {} vertices and {} triangles)",
        a.out.display(),
        skeleton.joints().len(),
        skin.helpers.len(),
        written.positions.len(),
        written.indices.len() / 3
    );
    Ok(ExitCode::SUCCESS)
}

/// Options of `troupe export urdf`.
#[derive(Args)]
struct UrdfArgs {
    /// The file to write.
    out: PathBuf,
    /// Body template.
    #[arg(long, default_value = "adult")]
    template: String,
    /// Standing height in metres (default: the template's).
    #[arg(long)]
    height: Option<f64>,
    /// Body mass in kilograms (default: the template's).
    #[arg(long)]
    mass: Option<f64>,
    /// Attach the pelvis (HumanoidRoot) to the base link with a fixed joint instead of the
    /// six root DOFs.
    #[arg(long)]
    fixed_root: bool,
}

/// Runs `troupe export`.
pub fn run(args: ExportArgs) -> Result<ExitCode> {
    // The output's folder is made as `troupe run --record` makes a recording's.
    let out = match &args.format {
        Format::Gltf(a) => &a.out,
        Format::Urdf(a) => &a.out,
    };
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    match args.format {
        Format::Gltf(a) => export_gltf(a),
        Format::Urdf(a) => {
            let t = troupe_body::template(&a.template)?;
            let d = t.default_params();
            let skeleton = t.instantiate(TemplateParams {
                height: a.height.unwrap_or(d.height),
                mass: a.mass.unwrap_or(d.mass),
            })?;
            let text = troupe_formats::urdf::urdf(&skeleton, a.fixed_root)?;
            std::fs::write(&a.out, &text)
                .with_context(|| format!("writing {}", a.out.display()))?;
            eprintln!(
                "wrote {} ({} joints, {} links)",
                a.out.display(),
                text.matches("\n  <joint ").count(),
                text.matches("<link ").count()
            );
            Ok(ExitCode::SUCCESS)
        }
    }
}
