//! # ftsmc-sim
//!
//! Everything around the control laws of `ftsmc-core`: truth models of the
//! vehicle, actuators, the environment, scenario files, the run loop,
//! metrics, the controllers (each declared once) and their registry, Monte
//! Carlo batches and analyses.
//!
//! ## Layout
//!
//! Modules are arranged on floors; a module only uses modules on its own
//! floor or below, never above (checked by `tests/layout.rs`):
//!
//! ```text
//! floor 7  falsify/             worst cases and rare failures (docs/falsification.md)
//!            search.rs          CMA-ES with IPOP restarts and uniform random search over the [falsify] box
//!            rare.rs            P(margin < 0) by cross-entropy importance sampling, and plain Monte Carlo
//!          tune/                `ftsmc tune`: parameter space, cost, CMA-ES, held-out validation
//!            cmaes.rs           ask/tell CMA-ES
//!            cost.rs            flight statistics and the tuning cost
//!            space.rs           declared + [tune] parameters, normalised coordinates, tuned TOML diff
//! floor 6  analysis/            analyses built on flights
//!            fixed_time.rs      fixed-time sweep, per-controller channel sweep, Eq. 38 bound
//!            tuning.rs          gain tuning
//!          batch/               batches of flights
//!            montecarlo.rs      run_batch, stats, summarize
//!            shard.rs           K/N shards of a campaign (contiguous blocks of runs)
//!          gym/                 reinforcement-learning environments (Python's `ftsmc.gym`)
//!            agent.rs           the agent as a controller: thrust + body rates, or rotor speeds
//!            lane.rs            one environment: an owned Flight, observation, reward, episode end
//!            batch.rs           N environments per call, next-step auto-reset
//! floor 5  registry.rs          controllers by name for a scenario: build, run, label
//! floor 4  run/                 the one loop (docs/architecture.md): simulate, RunOptions, RunOutput
//!            flight.rs          Flight: one flight, stepped one control period at a time
//!            actuation.rs       the actuator stage: ideal, per-rotor clamp, mixer + lagged motors
//!            truth.rs           TruthModel: paper Eq. 1 and the rigid body, RK4 substeps
//!            observer.rs        Tick, Observer, FlightStats (tilt, saturation, rotor statistics)
//!            exit.rs            ExitStatus, Divergence, divergence checks
//!            recording.rs       Recording, recording_columns, CSV numbers
//! floor 3  scenario/            the file format; composes every part's parameters; validation
//!            validate.rs        range checks, names, array lengths, cost limits
//!            resolve.rs         extends chains, deep merge, vehicle and wind presets, unit-slip warnings
//!            overrides.rs       dotted-key overrides: --set KEY=VALUE and Python's with_overrides
//!            distributions.rs   Dist, MonteCarloSpec, SAMPLED_COLUMNS, run_seed, per-run sampling
//!            ladder.rs          the wind ladder's built-in scenarios realistic-<level>-<n>
//!            tune_section.rs    `[tune]`: parameter set and cost weights of `ftsmc tune`
//!            falsify_section.rs `[falsify]`: bounded search space with nominal distributions, applied to a scenario
//!            deprecated.rs      old spellings ([actual_plant], [vehicle.rigid_body], max_tilt) moved to the new keys
//! floor 2  vehicle/             truth models
//!            paper.rs           Eq. 1 (the paper's plant) and the generic rk4_step
//!            rigid_body.rs      Newton–Euler rigid body with quaternion attitude
//!            math.rs            small vector/quaternion helpers
//!            section.rs         `[vehicle]`: the truth model and every true parameter, one key set
//!            presets.rs         named real vehicles (`[vehicle] preset`), their sourced files in vehicles/
//!          actuators.rs         motor limits, lag, noise; mixer under saturation
//!          environment/         plant-side variations, built from their own sections
//!            disturbance.rs     DisturbanceSignals
//!            payload.rs         Payload and its profile
//!            variation.rs       DragNoise (inertia variation is a Signal)
//!            ground.rs          ground plane, touchdown and crash (`[ground]`)
//!            wind.rs            mean wind, 1−cos gusts, Dryden turbulence (`[wind]`)
//!            phasors.rs         the environment's sinusoid terms on the loop's grid, four at a time
//!          envelope.rs          success envelope and its verdict (`[envelope]`)
//!          margin.rs            signed robustness margin to the envelope (STL robustness)
//!          metrics.rs           ISE, IAE, ITAE, settling, chattering, online
//!          sensors/             measured state: mocap.rs (`[sensors]`: noise, bias, sample rate, latency),
//!                               sensor stages imu, gnss, baro, mag and the estimator stage
//!          controllers/         each controller declared once: name, label, gain section, constructor
//!            tunable.rs         what `ftsmc tune` may change, by controller (declared in each file)
//!            tune_param.rs      TuneParam / TuneTarget: the type of a declared tune parameter
//!            mod.rs             the Declaration/GainSection traits and the one list (GainSections, CONTROLLERS)
//!            ftaftsmc.rs        `ftaftsmc`, `ftaftsmc-no-mass` (`[ftaftsmc]`)
//!            ranftsmc.rs        `ranftsmc` (`[ranftsmc]`)
//!            tsm_sta.rs         `tsm-sta` (`[tsm-sta]`)
//!            per_lane.rs        any one-flight controller on lanes (one controller per lane)
//!            on_isa.rs          a controller's updates on the instruction set picked at run time
//! floor 1  axes.rs              AxisSet and other per-axis containers
//!          trajectory/          3-D trajectories with heading, exact to snap (`[reference] trajectory`)
//!            min_snap.rs        minimum snap through waypoints, closed form, banded Cholesky
//!            library.rs         hover, circle, oval, figure-eight, lissajous, helix, star, trefoil, ramp
//!            feasibility.rs     thrust, tilt and body rates by differential flatness, and time fitting
//!          defaults.rs          the defaults of every campaign (runs, budgets, confidence), read by the CLI and Python
//!          desaturation.rs      PX4's sequential-desaturation allocation (airmode off)
//!          signal/              time signals with analytic derivatives
//!            waypoints.rs       quintic waypoint splines
//!          limits.rs            cost limits and their arithmetic
//!          text.rs              values in error messages, exact-length TOML arrays
//!          isa.rs               the instruction set of the lane kernels, picked at run time
//!          noise.rs             NoiseStream: a noise source's ChaCha generator read a block ahead
//! floor 0  rng.rs               the ChaCha8 generator of a seed on a stream: every draw starts there
//!          gauss.rs             normal and log-normal draws (ziggurat) on the libm crate's exp and ln
//!          stats/               intervals (rates, quantiles, means), paired tests, Holm, sequential looks
//! ```
#![warn(missing_docs)]

pub mod actuators;
pub mod analysis;
pub mod axes;
pub mod batch;
pub mod controllers;
pub mod defaults;
pub mod desaturation;
pub mod envelope;
pub mod environment;
pub mod escape;
pub mod falsify;
pub mod gauss;
pub mod gym;
pub mod isa;
pub mod limits;
pub mod margin;
pub mod metrics;
pub mod noise;
pub mod registry;
pub mod rng;
pub mod run;
pub mod scenario;
pub mod sensors;
pub mod signal;
pub mod stats;
pub mod text;
pub mod trajectory;
pub mod tune;
pub mod vehicle;

pub use run::{simulate, ExitStatus, RunOptions, RunOutput};
pub use scenario::{Scenario, ScenarioError};
