//! N environments stepped in one call, with Gymnasium's next-step
//! auto-reset: a lane whose episode ended at one call is reset (with the
//! seed given for it) at the next call, which ignores its action and
//! reports reward 0, not terminated, not truncated.

use rayon::prelude::*;

use super::lane::{Env, EnvStep, Pose};
use super::{GymSpec, ACTION_LEN, OBSERVATION_LEN};

/// Lanes from this many on are stepped on rayon's pool (each lane is
/// independent, so the bits do not depend on the thread count).
const PARALLEL_FROM: usize = 16;

/// The outputs of [`Batch::step`] and [`Batch::reset`], one entry per lane
/// (`observation` holds `OBSERVATION_LEN` numbers per lane, row-major).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepResult {
    /// Observations, `N × OBSERVATION_LEN`.
    pub observation: Vec<f32>,
    /// Rewards.
    pub reward: Vec<f64>,
    /// Episode ended by a crash or divergence.
    pub terminated: Vec<bool>,
    /// Episode reached its end time.
    pub truncated: Vec<bool>,
    /// Why the episode ended (empty while it goes on).
    pub reason: Vec<String>,
    /// Time into the episode, s.
    pub time: Vec<f64>,
    /// The lane was reset by this call (auto-reset).
    pub reset: Vec<bool>,
}

impl StepResult {
    fn clear(&mut self, n: usize) {
        self.observation.clear();
        self.observation.reserve(n * OBSERVATION_LEN);
        for v in [&mut self.terminated, &mut self.truncated, &mut self.reset] {
            v.clear();
        }
        self.reward.clear();
        self.reason.clear();
        self.time.clear();
    }
}

/// N environments of one [`GymSpec`].
pub struct Batch {
    spec: GymSpec,
    lanes: Vec<Env>,
    done: Vec<bool>,
}

struct Out {
    observation: [f64; OBSERVATION_LEN],
    step: EnvStep,
    time: f64,
    reset: bool,
}

impl Batch {
    /// `seeds.len()` lanes, lane `i` starting an episode seeded `seeds[i]`.
    pub fn new(spec: GymSpec, seeds: &[u64]) -> Self {
        let lanes = seeds.iter().map(|&s| Env::new(&spec, s)).collect();
        Self { done: vec![false; seeds.len()], spec, lanes }
    }

    /// Number of lanes.
    pub fn len(&self) -> usize {
        self.lanes.len()
    }

    /// True without lanes.
    pub fn is_empty(&self) -> bool {
        self.lanes.is_empty()
    }

    /// The spec.
    pub fn spec(&self) -> &GymSpec {
        &self.spec
    }

    /// Seed of lane `i`'s current episode.
    pub fn seed(&self, i: usize) -> u64 {
        self.lanes[i].seed()
    }

    /// The true pose of lane `i`'s vehicle (for drawing it).
    pub fn pose(&mut self, i: usize) -> Pose {
        self.lanes[i].pose()
    }

    /// Lanes whose episode ended at the last step (reset at the next).
    pub fn done(&self) -> &[bool] {
        &self.done
    }

    fn each<F>(&mut self, f: F) -> Vec<Out>
    where
        F: Fn(usize, &GymSpec, &mut Env, bool) -> Out + Sync,
    {
        let spec = &self.spec;
        let done = &self.done;
        if self.lanes.len() >= PARALLEL_FROM {
            self.lanes.par_iter_mut().enumerate().with_min_len(4).map(|(i, l)| f(i, spec, l, done[i])).collect()
        } else {
            self.lanes.iter_mut().enumerate().map(|(i, l)| f(i, spec, l, done[i])).collect()
        }
    }

    fn write(&mut self, outs: Vec<Out>, into: &mut StepResult) {
        into.clear(outs.len());
        for (i, o) in outs.into_iter().enumerate() {
            into.observation.extend(o.observation.iter().map(|&v| v as f32));
            into.reward.push(o.step.reward);
            into.terminated.push(o.step.terminated);
            into.truncated.push(o.step.truncated);
            self.done[i] = o.step.terminated || o.step.truncated;
            into.reason.push(o.step.reason.unwrap_or_default());
            into.time.push(o.time);
            into.reset.push(o.reset);
        }
    }

    /// Start a new episode in every lane, lane `i` seeded `seeds[i]`
    /// (`seeds.len()` must be [`Batch::len`]).
    pub fn reset(&mut self, seeds: &[u64], into: &mut StepResult) {
        assert_eq!(seeds.len(), self.lanes.len(), "one seed per lane");
        let outs = self.each(|i, spec, lane, _| {
            *lane = Env::new(spec, seeds[i]);
            Out { observation: lane.observe(), step: idle(), time: 0.0, reset: true }
        });
        self.write(outs, into);
    }

    /// One environment step in every lane: `actions` holds `ACTION_LEN`
    /// numbers per lane (row-major); a lane whose episode ended at the last
    /// call is reset instead, seeded `reset_seeds[i]` (read only for those).
    pub fn step(&mut self, actions: &[f64], reset_seeds: &[u64], into: &mut StepResult) {
        assert_eq!(actions.len(), self.lanes.len() * ACTION_LEN, "ACTION_LEN actions per lane");
        assert_eq!(reset_seeds.len(), self.lanes.len(), "one reset seed per lane");
        let outs = self.each(|i, spec, lane, done| {
            if done {
                *lane = Env::new(spec, reset_seeds[i]);
                return Out { observation: lane.observe(), step: idle(), time: 0.0, reset: true };
            }
            let mut a = [0.0; ACTION_LEN];
            a.copy_from_slice(&actions[i * ACTION_LEN..(i + 1) * ACTION_LEN]);
            let step = lane.step(spec, a);
            Out { observation: lane.observe(), step, time: lane.time(), reset: false }
        });
        self.write(outs, into);
    }
}

fn idle() -> EnvStep {
    EnvStep { reward: 0.0, terminated: false, truncated: false, reason: None }
}
