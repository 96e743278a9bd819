//! Background work at a lower CPU priority, so the window stays responsive on machines where the
//! GPU is a software rasterizer sharing the CPU with the UI.
//!
//! On Linux the nice value is per thread and threads inherit it from the thread that creates them:
//! lowering the render worker's priority before it creates its device also lowers the rasterizer
//! threads Mesa's llvmpipe spawns for that device (and rayon's pool, for the plots thread). The
//! editor's own thread, and its GL context's threads, keep the normal priority.

/// Nice value of background threads.
const NICE: &str = "10";

/// Lower the calling thread's priority (best effort: does nothing where it cannot).
pub fn lower_current_thread() {
    #[cfg(target_os = "linux")]
    {
        // "/proc/thread-self" links to "<pid>/task/<tid>".
        let Ok(link) = std::fs::read_link("/proc/thread-self") else {
            return;
        };
        let Some(tid) = link.file_name().and_then(|t| t.to_str()).map(str::to_owned) else {
            return;
        };
        let status = std::process::Command::new("renice")
            .args(["-n", NICE, "-p", &tid])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .status();
        if !status.is_ok_and(|s| s.success()) {
            log::debug!("could not lower the priority of thread {tid}");
        }
    }
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    /// The calling thread's nice value, from /proc.
    fn nice_of_current_thread() -> Option<i64> {
        let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
        // Field 19 (1-based) is the nice value; fields after the ")" of the command name.
        let rest = stat.rsplit_once(')')?.1;
        rest.split_whitespace().nth(16)?.parse().ok()
    }

    #[test]
    fn lowers_only_the_calling_thread() {
        let main_before = nice_of_current_thread();
        let worker = std::thread::spawn(|| {
            super::lower_current_thread();
            nice_of_current_thread()
        })
        .join()
        .expect("thread");
        if worker.is_none()
            || std::process::Command::new("renice")
                .arg("--version")
                .output()
                .is_err()
        {
            eprintln!("skipped: no /proc or renice");
            return;
        }
        assert!(worker >= Some(10), "{worker:?}");
        assert_eq!(nice_of_current_thread(), main_before);
    }
}
