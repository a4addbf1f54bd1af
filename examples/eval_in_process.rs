//! The in-process time of `rigport eval` (`rigport_pipeline::eval`: the import, the
//! sampling and skinning of every frame, the `.npz` written), for the Python bindings'
//! benchmark (`benches/python_evaluate.py`, BENCHMARKS.md "Python bindings"): the process
//! start and argument parsing are left out, as they are for the Python call it is compared
//! with.
//!
//! ```text
//! cargo run --release --example eval_in_process -- --fps 25 --runs 10 arms.glb
//! ```
//! prints one line: `eval_in_process: <median s> s median of <runs> runs (<each>)`; with
//! `--in-memory`, times what the Python call runs instead (the import and
//! `rigport_pipeline::eval::evaluate`, the arrays kept in memory, no `.npz`).

use std::path::PathBuf;
use std::time::Instant;

use rigport_pipeline::eval::{evaluate, EvalOptions, Evaluation};
use rigport_pipeline::load::Input;
use rigport_pipeline::progress::Silent;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    rigport_pipeline::memory::raise_malloc_mmap_threshold();
    let mut fps = None;
    let mut runs = 10;
    let mut paths = Vec::new();
    let mut in_memory = false;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--fps" => fps = Some(args.next().ok_or("--fps needs a value")?.parse()?),
            "--runs" => runs = args.next().ok_or("--runs needs a value")?.parse()?,
            "--in-memory" => in_memory = true,
            _ => paths.push(PathBuf::from(arg)),
        }
    }
    let dir = tempfile::tempdir()?;
    let options = EvalOptions {
        fps,
        output: dir.path().join("frames.npz"),
        ..EvalOptions::default()
    };
    let input = Input {
        budget: rigport_pipeline::memory::DEFAULT,
        ..Input::new(paths)
    };
    let once = || -> Result<(), Box<dyn std::error::Error>> {
        if in_memory {
            let (plan, imported) = input.load_single(&Silent, "reading")?;
            let request = Evaluation {
                fps: options.fps,
                ..Evaluation::default()
            };
            std::hint::black_box(evaluate(
                &imported.asset,
                &plan.label(),
                &request,
                &input.budget,
            )?);
        } else {
            rigport_pipeline::eval(&input, &options, &Silent)?;
        }
        Ok(())
    };
    // One warm-up run (page cache, allocator), then the timed runs.
    once()?;
    let mut seconds = Vec::with_capacity(runs);
    for _ in 0..runs {
        let start = Instant::now();
        once()?;
        seconds.push(start.elapsed().as_secs_f64());
    }
    let mut sorted = seconds.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let each: Vec<String> = seconds.iter().map(|s| format!("{s:.4}")).collect();
    println!(
        "eval_in_process: {median:.4} s median of {runs} runs ({})",
        each.join(" ")
    );
    Ok(())
}
