//! The Crazyflie firmware's controllers (`crazyflie-pid`, `mellinger`)
//! flown as scenarios on the `crazyflie-2.1` preset at the firmware's
//! 500 Hz: they take off from rest to 1 m and hold it, and a position step
//! converges; their sections follow the vehicle's rotor limit.

use ftsmc_sim::controllers::{GainSection, NominalVehicle};
use ftsmc_sim::registry;
use ftsmc_sim::run::RunOptions;
use ftsmc_sim::scenario::Scenario;

fn scenario(reference: &str) -> Scenario {
    let text = format!(
        "name = \"cf\"\nduration = 8.0\ncontrollers = [\"crazyflie-pid\", \"mellinger\"]\n\
         [simulation]\ncontrol_rate = 500.0\n\
         [vehicle]\npreset = \"crazyflie-2.1\"\n[ground]\nenabled = true\n\
         [reference]\n{reference}\n"
    );
    Scenario::from_toml_str(&text, "cf.toml").unwrap()
}

#[test]
fn both_hold_a_hover_and_converge_after_a_step_on_the_crazyflie() {
    let hover = scenario("z = { terms = [{ type = \"constant\", value = 1.0 }] }");
    let step = scenario(
        "x = { terms = [{ type = \"step\", time = 2.0, height = 0.5 }] }\n\
         z = { terms = [{ type = \"constant\", value = 1.0 }] }",
    );
    for c in ["crazyflie-pid", "mellinger"] {
        for s in [&hover, &step] {
            let out = registry::run(c, s, RunOptions::default()).unwrap();
            assert!(out.exit.is_completed(), "{c}: {}", out.exit);
            // After 5 s (simulation.steady_state_after), within 10 cm on every axis.
            let m = &out.metrics.max_error_after;
            for (axis, e) in [("x", m.x), ("y", m.y), ("z", m.z)] {
                let e = e.unwrap();
                assert!(e < 0.1, "{c}: {axis} error {e} m after 5 s");
            }
        }
    }
}

#[test]
fn the_motor_map_follows_the_vehicle() {
    let s = scenario("z = { terms = [{ type = \"constant\", value = 1.0 }] }");
    assert_eq!(s.gains.crazyflie_pid.motors.max_rotor_speed, 2618.0);
    assert_eq!(s.gains.mellinger.motors.max_rotor_speed, 2618.0);
    // Unlimited rotors: the top speed at which 36000 hovers the vehicle.
    let v = NominalVehicle::default();
    let g = <ftsmc_core::crazyflie_pid::CrazyfliePidGains as GainSection>::defaults_for(&v);
    let w = g.motors.max_rotor_speed * 36000.0 / 65535.0;
    let hover = 4.0 * v.plant.lift_coefficient * w * w;
    assert!((hover / (v.plant.mass * v.plant.gravity) - 1.0).abs() < 1e-12);
}
