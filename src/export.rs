//! `troupe export urdf OUT.urdf`: a body template as URDF, for dynamics and robotics tools
//! (the writer and its conventions are [`troupe_formats::urdf`]); `troupe export gltf
//! OUT.glb`: a body template as a skinned glTF character (its generated skin bound to its
//! joints).

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
    /// Write a body template as a skinned glTF character (.gltf + .bin, or .glb).
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
}

/// Writes the skinned character of `a` at rest.
fn export_gltf(a: GltfArgs) -> Result<ExitCode> {
    let t = troupe_body::template(&a.template)?;
    let d = t.default_params();
    let skeleton = t.instantiate(TemplateParams {
        height: a.height.unwrap_or(d.height),
        mass: a.mass.unwrap_or(d.mass),
    })?;
    let skin = troupe_body::Skin::build(&skeleton)?;
    let rest = troupe_motion::sequence::Sequence::new("rest");
    let rig = troupe_formats::Rig::from_sequence(&skeleton, &rest)?;
    troupe_formats::save_skinned(&a.out, &rig, Some(&skin), &a.template)
        .with_context(|| format!("writing {}", a.out.display()))?;
    eprintln!(
        "wrote {} ({} joints, a skin of {} vertices and {} triangles)",
        a.out.display(),
        skeleton.joints().len(),
        skin.positions.len(),
        skin.triangle_count()
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
