//! SIGINT and SIGTERM: remove the temporary files of unfinished outputs, then exit with
//! 128 + the signal number (130, 143), as a shell reports a process the signal ended.
//!
//! Outputs are written to `.<name>.<pid>.<n>.tmp` and renamed ([`crate::write_atomic`]);
//! a signal's default action would end the process and leave such a file behind. A process
//! killed outright (SIGKILL) still leaves one; the next write into that folder sweeps it.

/// Starts a thread that waits for SIGINT or SIGTERM, then removes every live temporary
/// file ([`crate::remove_temp_files`]) and exits. Without it (it cannot be set up,
/// or not on Unix) the signals keep their default action.
///
/// ```no_run
/// rigport_atomic::remove_temp_files_on_interrupt();
/// ```
pub fn remove_temp_files_on_interrupt() {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGINT, SIGTERM};
        use signal_hook::iterator::Signals;
        // Registered in the thread: if it cannot start, the signals keep their default
        // action instead of being caught by nobody.
        let _spawned = std::thread::Builder::new()
            .name("signals".into())
            .spawn(|| {
                let Ok(mut signals) = Signals::new([SIGINT, SIGTERM]) else {
                    return;
                };
                if let Some(signal) = signals.forever().next() {
                    crate::remove_temp_files();
                    std::process::exit(128 + signal);
                }
            });
    }
}
