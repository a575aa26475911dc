//! `troupe templates`: the body templates, their DOF counts, scopes and (optionally) DOFs.

use anyhow::Result;
use clap::Args;
use std::process::ExitCode;
use troupe_body::{templates, DofKind};

/// Options of `troupe templates`.
#[derive(Args)]
pub struct TemplatesArgs {
    /// Also list every DOF of each template with its axis and limits.
    #[arg(long)]
    dofs: bool,
    /// Only this template.
    name: Option<String>,
}

/// Prints the listing.
pub fn run(args: TemplatesArgs) -> Result<ExitCode> {
    let all = templates();
    let chosen: Vec<_> = match &args.name {
        Some(n) => vec![troupe_body::template(n)?],
        None => all,
    };
    for t in chosen {
        let skeleton = t.instantiate(t.default_params())?;
        let hands = skeleton.scope("hands")?.len();
        println!(
            "{}: {} (default height {} m, mass {} kg)",
            t.name, t.description, t.default_height, t.default_mass
        );
        println!(
            "  {} joints, {} DOFs ({} body incl. 6 root, {} hands), {} solids",
            skeleton.joints().len(),
            skeleton.dof_count(),
            skeleton.dof_count() - hands,
            hands,
            skeleton.solids().len()
        );
        println!("  scopes:");
        for (name, scope) in skeleton.scopes() {
            println!("    {name:<12} {:>3} DOFs", scope.len());
        }
        if args.dofs {
            println!("  DOFs (limits in degrees, or metres for translations):");
            for d in skeleton.dofs() {
                let joint = &skeleton.joints()[d.joint].name;
                let (unit, min, max) = match d.kind {
                    DofKind::Rotation => ("rot", d.min.to_degrees(), d.max.to_degrees()),
                    DofKind::Translation => ("trans", d.min, d.max),
                };
                println!(
                    "    {:<30} {:<18} {:<5} axis ({:+.3}, {:+.3}, {:+.3})  [{:.0}, {:.0}]",
                    d.name, joint, unit, d.axis.x, d.axis.y, d.axis.z, min, max
                );
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
