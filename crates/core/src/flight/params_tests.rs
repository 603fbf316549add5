//! Tests of the parameter registry: the table's names and bounds, set-then-get, refusals that
//! change nothing, and a change of gains in flight.

extern crate std;

use super::*;
use crate::flight::autopilot::Autopilot;
use crate::flight::tests::{config, Flight};
use crate::msgs::FlightMode;
use proptest::prelude::*;

#[test]
fn names_fit_mavlink_are_unique_and_defaults_lie_within_bounds() {
    assert!(count() > 60);
    for i in 0..count() {
        let p = info(i).unwrap();
        assert!(!p.name.is_empty() && p.name.len() <= 16, "{}", p.name);
        assert!(p
            .name
            .bytes()
            .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit() || b == b'_'));
        assert_eq!(find(p.name), Some(i), "{} is not unique", p.name);
        assert!(p.min < p.max && !p.unit.is_empty() && !p.doc.is_empty());
        let d = default_value(i).unwrap();
        assert!((p.min..=p.max).contains(&d), "{} default {d}", p.name);
        // The airframe-fitted configuration starts within bounds too.
        let fitted = get(&config(), i).unwrap();
        assert!(
            (p.min..=p.max).contains(&fitted),
            "{} fitted {fitted}",
            p.name
        );
    }
    assert_eq!(info(count()).map(|p| p.name), None);
    assert_eq!(find("PID_POS_XY_P\0"), None);
    assert_eq!(find("NO_SUCH_PARAM"), None);
}

#[test]
fn refusals_say_why() {
    let c = AutopilotConfig::default();
    let kp = find("PID_POS_XY_P").unwrap();
    assert_eq!(with(&c, count(), 1.0, false), Err(ParamError::Unknown));
    assert_eq!(with(&c, kp, f32::NAN, false), Err(ParamError::NotFinite));
    assert_eq!(
        with(&c, kp, f32::INFINITY, false),
        Err(ParamError::NotFinite)
    );
    assert_eq!(
        with(&c, kp, 0.0, false),
        Err(ParamError::OutOfRange { min: 0.1, max: 5.0 })
    );
    let crit = find("FS_BATT_CRIT_V").unwrap();
    assert!(matches!(
        with(&c, crit, c.supervisor.battery_low_v + 0.1, false),
        Err(ParamError::Inconsistent { .. })
    ));
    // A heavy vehicle hovers at 0.6: a collective bound of 0.55 could not hold it up.
    let mut heavy = c;
    heavy.cascade.hover_collective = 0.6;
    let max = find("CTL_COLL_MAX").unwrap();
    assert!(with(&c, max, 0.55, false).is_ok());
    assert!(matches!(
        with(&heavy, max, 0.55, false),
        Err(ParamError::Inconsistent { .. })
    ));
    let width = find("MRAC_RBF_WIDTH").unwrap();
    assert_eq!(with(&c, width, 1.0, true), Err(ParamError::NotWhileArmed));
    assert!(with(&c, width, 1.0, false).is_ok());
}

proptest! {
    #[test]
    fn a_value_within_bounds_reads_back_exactly(index in 0usize..75, frac in 0.0f32..=1.0) {
        let p = info(index % count()).unwrap();
        let index = index % count();
        let value = p.min + frac * (p.max - p.min);
        let mut ap = Autopilot::new(AutopilotConfig::default());
        match ap.set_param(index, value) {
            Ok(v) => {
                prop_assert_eq!(v, value);
                prop_assert_eq!(ap.param(index), Some(value));
            }
            // Only a rule between parameters may refuse a value within bounds.
            Err(e) => {
                prop_assert!(matches!(e, ParamError::Inconsistent { .. }), "{:?}", e);
                prop_assert_eq!(ap.config, AutopilotConfig::default());
            }
        }
    }

    #[test]
    fn a_value_out_of_range_never_changes_the_config(
        index in 0usize..75,
        value in prop_oneof![
            any::<f32>(),
            Just(f32::NAN),
            Just(f32::INFINITY),
            Just(f32::NEG_INFINITY),
            -1e6f32..1e6,
        ],
    ) {
        let index = index % count();
        let p = info(index).unwrap();
        prop_assume!(!(p.min..=p.max).contains(&value));
        let mut ap = Autopilot::new(config());
        let before = ap.config;
        prop_assert!(ap.set_param(index, value).is_err());
        prop_assert_eq!(ap.config, before);
        prop_assert_eq!(ap.param(index), get(&before, index));
    }
}

#[test]
fn gains_changed_in_a_hold_take_effect_without_a_jump() {
    let mut f = Flight::new(config(), 21);
    f.take_off();
    f.fly(3.0);
    let before = f.out.motors.throttle_norm;
    for (name, value) in [
        ("PID_VEL_XY_I", 0.5),
        ("PID_VEL_XY_IMAX", 0.5),
        ("PID_POS_XY_P", 1.0),
        ("PID_RATE_RP_I", 10.0),
        ("FS_LIDAR_TMO", 2.0),
    ] {
        let i = find(name).unwrap();
        assert_eq!(f.ap.set_param(i, value), Ok(value), "{name}");
        assert_eq!(f.ap.param(i), Some(value));
    }
    assert_eq!(f.ap.config.cascade.velocity_xy.ki, 0.5);
    f.fly(0.002);
    let after = f.out.motors.throttle_norm;
    for (b, a) in before.iter().zip(&after) {
        assert!((a - b).abs() < 0.02, "{before:?} -> {after:?}");
    }
    // Still holding on the new gains.
    f.fly(5.0);
    assert_eq!(f.out.mode, FlightMode::Hold);
    assert!(f.horizontal_error_m() < 0.05, "{}", f.horizontal_error_m());
    // A structural MRAC parameter waits for the ground.
    let width = find("MRAC_RBF_WIDTH").unwrap();
    assert_eq!(f.ap.set_param(width, 1.0), Err(ParamError::NotWhileArmed));
    assert_eq!(f.ap.param(width), get(&config(), width));
}
