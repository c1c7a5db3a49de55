//! Paired verdicts rest on the pairing: in one batch every controller
//! flies run `i`'s draws (vehicle, wind, noise seed, initial state), and
//! adding or reordering contestants does not move them.

use ftsmc_sim::batch::montecarlo::{run_batch, summarize, BatchOptions};
use ftsmc_sim::batch::verdicts::{intervals, pairwise, Outcomes};
use ftsmc_sim::scenario::ladder::LADDER;
use ftsmc_sim::scenario::Scenario;

fn breeze() -> Scenario {
    let (file, text) = LADDER.iter().find(|(f, _)| f.contains("breeze-1")).expect("the ladder has a breeze rung");
    let mut s = Scenario::from_toml_str(text, file).unwrap();
    s.duration = 4.0;
    s
}

#[test]
fn controllers_in_one_batch_fly_the_same_draws() {
    let s = breeze();
    let spec = s.montecarlo.clone().unwrap();
    let names = |v: &[&str]| v.iter().map(|n| n.to_string()).collect::<Vec<_>>();
    let both = run_batch(&s, &spec, &names(&["pid", "se3"]), BatchOptions::new(6, s.seed)).unwrap();
    let alone = run_batch(&s, &spec, &names(&["se3"]), BatchOptions::new(6, s.seed)).unwrap();
    for i in 0..6u64 {
        let rows: Vec<_> = both.iter().filter(|r| r.index == i).collect();
        assert_eq!(rows.len(), 2);
        // Same seed and the same sampled vehicle for both contestants …
        assert_eq!(rows[0].seed, rows[1].seed);
        assert_eq!(rows[0].sampled.map(f64::to_bits), rows[1].sampled.map(f64::to_bits));
        // … and SE(3)'s run is the same flight whoever else is in the batch.
        let one = alone.iter().find(|r| r.index == i).unwrap();
        assert_eq!(one.seed, rows[1].seed);
        assert_eq!(one.metrics.rms.to_array().map(f64::to_bits), rows[1].metrics.rms.to_array().map(f64::to_bits));
    }
    // Every written summary row has lo ≤ estimate ≤ hi.
    for (_, c) in summarize(&both, &names(&["pid", "se3"])) {
        let i = &c.intervals;
        for r in [i.success_rate, i.completed_rate, i.crashed_rate, i.diverged_rate] {
            assert!(r.lo <= r.estimate && r.estimate <= r.hi, "{r:?}");
        }
        for r in [i.rms_median, i.rms_p95, i.rms_mean].into_iter().flatten() {
            assert!(r.lo <= r.estimate && r.estimate <= r.hi, "{r:?}");
        }
    }
}

#[test]
fn a_controller_against_itself_shows_no_difference() {
    let mut o = Outcomes::default();
    for k in 0..30 {
        o.push(k % 7 != 0, true, false, 0.1 + 0.01 * f64::from(k));
    }
    let v = pairwise(&[("a".into(), &o), ("b".into(), &o)], 0.95).unwrap();
    assert!(v.iter().all(|p| p.sentence() == "no difference shown"), "{v:?}");
    let i = intervals(&o, 0.95).unwrap();
    assert!(i.success_rate.lo < i.success_rate.estimate && i.success_rate.estimate < i.success_rate.hi);
}
