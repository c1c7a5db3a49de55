//! The instruction set the lane kernels run with, picked at run time.
//!
//! The default binary is built for baseline x86-64 (SSE2), so it runs on
//! every x86-64 CPU and builds for aarch64. The heavy arithmetic of flights
//! in lanes (the control laws and the truth model on `Lanes<N>`,
//! [`ftsmc_core::lanes`]) is compiled a second time with AVX2 and FMA
//! enabled ([`avx2_fma`]) and flies that way when the CPU has both
//! ([`Isa::detect`]). The numbers do not change: Rust never fuses a
//! multiply and an add unless asked to, every operation of the lanes is the
//! IEEE 754 operation of `f64` on each lane, and the transcendental
//! functions are the one maths library's on every path; only the width of
//! the instructions does (`tests/lanes.rs` and the CLI's `cpu_levels` test
//! compare the bits of both paths).
//!
//! `FTSMC_ISA=baseline` in the environment forces the baseline path (to
//! compare, or to rule the wider path out); `FTSMC_ISA=avx2` asks for the
//! wider path and falls back to baseline when the CPU lacks it.

use std::sync::OnceLock;

/// The instruction sets the lane kernels can run with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// What the binary was built for (SSE2 on x86-64, NEON on aarch64).
    Baseline,
    /// x86-64 with AVX2 and FMA (four `f64` per instruction).
    Avx2Fma,
}

impl Isa {
    /// The set this process uses: the widest the CPU has, unless
    /// `FTSMC_ISA=baseline` says otherwise. Detected once.
    pub fn detect() -> Isa {
        static CHOSEN: OnceLock<Isa> = OnceLock::new();
        *CHOSEN.get_or_init(|| {
            let forced_baseline = std::env::var("FTSMC_ISA").is_ok_and(|v| v.eq_ignore_ascii_case("baseline"));
            if !forced_baseline && cpu_has_avx2_fma() {
                Isa::Avx2Fma
            } else {
                Isa::Baseline
            }
        })
    }

    /// Its name as the CLI prints it.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Baseline => "baseline",
            Isa::Avx2Fma => "avx2+fma",
        }
    }
}

#[cfg(target_arch = "x86_64")]
fn cpu_has_avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

#[cfg(not(target_arch = "x86_64"))]
fn cpu_has_avx2_fma() -> bool {
    false
}

/// Run `f` compiled with AVX2 and FMA enabled: `f` and whatever it inlines
/// (the lane kernels mark their entry points `#[inline]`) use the 256-bit
/// instructions.
///
/// # Safety
/// The CPU must have AVX2 and FMA ([`Isa::detect`] returned
/// [`Isa::Avx2Fma`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
pub unsafe fn avx2_fma<T>(f: impl FnOnce() -> T) -> T {
    f()
}

/// `f` on the instruction set `isa` (the same result, bit for bit, on either).
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn run_on<T>(isa: Isa, f: impl FnOnce() -> T) -> T {
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Isa::Avx2Fma` is only chosen when the CPU has AVX2 and FMA.
        Isa::Avx2Fma => unsafe { avx2_fma(f) },
        _ => f(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_paths_compute_the_same_bits() {
        let x: Vec<f64> = (0..64).map(|i| 0.37 * i as f64 - 11.0).collect();
        let work = || x.iter().map(|v| (v * 1.1 + 0.3) / (v * v + 1.0)).map(f64::to_bits).collect::<Vec<_>>();
        assert_eq!(run_on(Isa::detect(), work), work());
        assert_eq!(run_on(Isa::Baseline, work), work());
    }
}
