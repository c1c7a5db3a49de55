//! The rigid body's per-period mass and inertia update
//! (`RigidBody::set_mass_and_scaled_inertia`, the payload and inertia
//! variation of a flight) gives the very body `with_mass_and_inertia`
//! builds after its full check, and refuses what that check refuses.

use ftsmc_sim::vehicle::rigid_body::{RigidBody, RigidBodyParams};

fn base() -> RigidBodyParams {
    RigidBodyParams {
        inertia: [[3.65e-3, 1e-5, -2e-5], [1e-5, 3.68e-3, 3e-6], [-2e-5, 3e-6, 7.03e-3]],
        ..RigidBodyParams::hummingbird()
    }
}

#[test]
fn the_fast_update_is_the_checked_body_bit_for_bit() {
    let p = base();
    let body = RigidBody::new(p).unwrap();
    for (mass, scale) in [(0.5, 1.0), (0.6, 0.7), (0.55, 1.4), (0.5, 1.0 + 1e-13), (2.0, 0.123_456_789)] {
        let inertia = p.inertia.map(|r| r.map(|v| v * scale));
        let checked = body.with_mass_and_inertia(mass, inertia).unwrap();
        let mut fast = body;
        fast.set_mass_and_scaled_inertia(mass, &p.inertia, scale).unwrap();
        assert_eq!(fast, checked, "mass {mass}, scale {scale}");
    }
}

#[test]
fn the_fast_update_refuses_what_the_check_refuses_and_keeps_the_body() {
    let p = base();
    let body = RigidBody::new(p).unwrap();
    for (mass, scale) in
        [(0.5, 0.0), (0.5, -1.0), (0.5, f64::NAN), (0.5, f64::INFINITY), (0.5, 1e12), (0.0, 1.0), (2e6, 1.0)]
    {
        let inertia = p.inertia.map(|r| r.map(|v| v * scale));
        let checked = body.with_mass_and_inertia(mass, inertia).map(|_| ()).unwrap_err();
        let mut fast = body;
        let err = fast.set_mass_and_scaled_inertia(mass, &p.inertia, scale).unwrap_err();
        assert_eq!(
            (err.field, err.value.to_bits(), err.expected),
            (checked.field, checked.value.to_bits(), checked.expected)
        );
        assert_eq!(fast, body, "a refused update leaves the body as it was");
    }
}

/// A payload alone (the inertia scale unchanged) moves only the mass:
/// `set_mass` gives the body `with_mass_and_inertia` builds with the same
/// inertia, and refuses (with the same error, the body unchanged) a mass
/// the check refuses.
#[test]
fn the_mass_only_update_is_the_checked_body_and_refuses_what_it_refuses() {
    let p = base();
    let mut scaled = RigidBody::new(p).unwrap();
    scaled.set_mass_and_scaled_inertia(0.6, &p.inertia, 1.3).unwrap();
    for body in [RigidBody::new(p).unwrap(), scaled] {
        let inertia = body.params().inertia;
        for mass in [0.5, 0.87, 1e-6, 1e6] {
            let mut fast = body;
            fast.set_mass(mass).unwrap();
            assert_eq!(fast, body.with_mass_and_inertia(mass, inertia).unwrap(), "mass {mass}");
        }
        for mass in [0.0, -1.0, 2e6, f64::NAN, f64::INFINITY] {
            let checked = body.with_mass_and_inertia(mass, inertia).map(|_| ()).unwrap_err();
            let mut fast = body;
            let err = fast.set_mass(mass).unwrap_err();
            assert_eq!(
                (err.field, err.value.to_bits(), err.expected),
                (checked.field, checked.value.to_bits(), checked.expected)
            );
            assert_eq!(fast, body, "a refused update leaves the body as it was");
        }
    }
}
