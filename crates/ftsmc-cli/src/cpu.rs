//! CPU time of this process, for the speed figures the commands print
//! (steps flown per CPU-second): wall time on a shared or busy machine
//! says little, CPU time says what the work cost.

/// User + system CPU time of this process and all its threads so far, s
/// (`getrusage(RUSAGE_SELF)`); `None` where that is not available.
pub fn process_cpu_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        // SAFETY: `getrusage` only writes the `rusage` we pass; zeroed is
        // a valid `rusage` (plain integers).
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        // SAFETY: `usage` is a valid, writable `rusage`.
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } != 0 {
            return None;
        }
        let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
        Some(seconds(usage.ru_utime) + seconds(usage.ru_stime))
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// "`S` M steps flown per CPU-second" from the steps flown and the CPU
/// seconds they took, or "" when the CPU time is unknown or zero.
pub fn steps_per_cpu_second(steps: u64, cpu_seconds: Option<f64>) -> String {
    match cpu_seconds {
        Some(cpu) if cpu > 0.0 => {
            format!(", {cpu:.2} CPU-s, {:.2} M steps flown per CPU-second", steps as f64 / cpu / 1e6)
        }
        _ => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_time_grows_with_work() {
        let Some(before) = process_cpu_seconds() else { return };
        let mut x = 0u64;
        for i in 0..50_000_000u64 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
        }
        std::hint::black_box(x);
        let after = process_cpu_seconds().unwrap();
        assert!(after > before, "{before} -> {after}");
    }

    #[test]
    fn the_figure_reads_in_millions() {
        assert_eq!(steps_per_cpu_second(3_000_000, Some(2.0)), ", 2.00 CPU-s, 1.50 M steps flown per CPU-second");
        assert_eq!(steps_per_cpu_second(3_000_000, None), "");
        assert_eq!(steps_per_cpu_second(3_000_000, Some(0.0)), "");
    }
}
