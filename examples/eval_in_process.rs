//! The in-process time of `rigport eval` (`rigport_pipeline::eval`: the import, the
//! sampling and skinning of every frame, the `.npz` written), for the Python bindings'
//! benchmark (`benches/python_evaluate.py`, BENCHMARKS.md "Python bindings"): the process
//! start and argument parsing are left out, as they are for the Python call it is compared
//! with.
//!
//! ```text
//! cargo run --release --example eval_in_process -- --fps 25 --runs 10 arms.glb
//! ```
//! prints one line: `eval_in_process: <median s> s median of <runs> runs (<each>)`.

use std::path::PathBuf;
use std::time::Instant;

use rigport_pipeline::eval::EvalOptions;
use rigport_pipeline::load::Input;
use rigport_pipeline::progress::Silent;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    rigport_pipeline::memory::raise_malloc_mmap_threshold();
    let mut fps = None;
    let mut runs = 10;
    let mut paths = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--fps" => fps = Some(args.next().ok_or("--fps needs a value")?.parse()?),
            "--runs" => runs = args.next().ok_or("--runs needs a value")?.parse()?,
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
    // One warm-up run (page cache, allocator), then the timed runs.
    rigport_pipeline::eval(&input, &options, &Silent)?;
    let mut seconds = Vec::with_capacity(runs);
    for _ in 0..runs {
        let start = Instant::now();
        rigport_pipeline::eval(&input, &options, &Silent)?;
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
