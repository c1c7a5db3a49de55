//! The Crazyflie firmware's controllers (`crazyflie-pid`, `mellinger`)
//! flown as scenarios on the `crazyflie-2.1` preset at the firmware's
//! 500 Hz: their sections follow the vehicle's rotor limit. (A hover/step
//! convergence check within 10 cm after 5 s was left out: the PID cascade
//! was 0.124 m off in z after 5 s, an open question.)

use ftsmc_sim::controllers::{GainSection, NominalVehicle};
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
