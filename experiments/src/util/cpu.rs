//! The CPU time of the process, which reports give beside wall times: the
//! fits of a run run concurrently, so their wall times alone overstate
//! what each cost.

/// Seconds of CPU time the process has used so far, on all its threads;
/// `None` where the platform cannot say.
pub fn process_cpu_secs() -> Option<f64> {
    #[cfg(unix)]
    {
        use nix::time::{ClockId, clock_gettime};
        clock_gettime(ClockId::CLOCK_PROCESS_CPUTIME_ID)
            .ok()
            .map(|t| t.tv_sec() as f64 + t.tv_nsec() as f64 * 1e-9)
    }
    #[cfg(not(unix))]
    {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn work_on_this_thread_shows_in_the_process_cpu_time() {
        let Some(before) = process_cpu_secs() else {
            return;
        };
        let mut x = 0.0f64;
        for i in 0..5_000_000 {
            x += (i as f64).sqrt();
        }
        std::hint::black_box(x);
        let after = process_cpu_secs().unwrap_or(before);
        assert!(after > before, "{before} → {after}");
    }
}
