//! `rigport inspect`: what is in a rig.

use std::io::Write;

use anyhow::Result;
use rigport_export::report::Report;

use crate::cli::InspectArgs;
use crate::context::Context;
use crate::input;

/// Runs `inspect`.
pub fn run(ctx: &Context, args: &InspectArgs) -> Result<()> {
    let mut reports = Vec::new();
    for plan in input::plans(&args.input)? {
        let imported = ctx.step(&format!("reading {}", plan.label()), || plan.import())?;
        // Warnings are part of the report; they do not go to stderr twice.
        let warnings = imported.warnings.iter().map(|w| w.labelled()).collect();
        if ctx.deny_warnings {
            ctx.report(&imported.warnings)?;
        }
        reports.push(Report::new(plan.label(), &imported.asset, warnings));
    }
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    if args.json {
        serde_json::to_writer_pretty(&mut out, &reports)?;
        writeln!(out)?;
    } else {
        for r in &reports {
            r.write_text(&mut out)?;
            for w in &r.warnings {
                writeln!(out, "  {w}")?;
            }
        }
    }
    out.flush()?;
    Ok(())
}
