//! `plumbline sim`'s model-error options: how the simulated vehicle differs from the one the
//! onboard software is configured for, and the gust storm. Each value is checked against its
//! documented range while the command line is parsed; the combination (can the vehicle still
//! hover?) is checked with the rest of the run before anything is written.

use crate::numeric::{within, Range};
use clap::Args;
use plumbline_sim::disturb::GustParams;
use plumbline_sim::runner::SimConfig;
use plumbline_sim::vehicle::model_error::{
    ModelError, Payload, WeakMotor, CG_OFFSET_RANGE_M, MASS_SCALE_RANGE, MOTOR_FACTOR_RANGE,
    PAYLOAD_RANGE_KG,
};
use serde_json::{json, Value};
use std::ops::RangeInclusive;

#[derive(Args, Debug)]
pub struct ModelErrorArgs {
    /// Model error: the simulated vehicle's mass and inertia are this multiple of the
    /// vehicle file's (the onboard software is not told). Valid range: [0.5, 2].
    #[arg(long, value_name = "SCALE", value_parser = within::<f64>(closed(&MASS_SCALE_RANGE)))]
    pub mass_scale: Option<f64>,
    /// Model error: motor MOTOR (1-4, numbered as in crates/sim/src/vehicle/mod.rs) gives
    /// FACTOR of its nominal thrust and hub moment. Valid FACTOR range: [0.5, 1].
    #[arg(long, value_name = "MOTOR,FACTOR", value_parser = parse_weak_motor)]
    pub weak_motor: Option<WeakMotor>,
    /// Model error: the centre of gravity sits this far from the rotors' centre, body x and y,
    /// m. Valid range of each: [-0.05, 0.05].
    #[arg(long, value_name = "X,Y", value_parser = parse_cg_offset, allow_hyphen_values = true)]
    pub cg_offset: Option<[f64; 2]>,
    /// Model error: a payload of KG carried from the start and dropped at T seconds. Valid
    /// ranges: KG [0, 1], T >= 0.
    #[arg(long, value_name = "KG,T", value_parser = parse_payload)]
    pub payload_drop: Option<Payload>,
    /// Gusts five times the indoor draughts' strength (1.5 m/s horizontal, 0.5 m/s vertical
    /// standard deviation) and four times as frequent (0.5 s correlation time).
    #[arg(long, conflicts_with = "no_gusts")]
    pub gust_storm: bool,
}

fn closed(r: &RangeInclusive<f64>) -> Range {
    Range::closed(*r.start(), *r.end())
}

/// Two comma-separated finite numbers.
fn pair(s: &str, what: &str) -> Result<[f64; 2], String> {
    let parts: Vec<&str> = s.split(',').collect();
    let numbers: Result<Vec<f64>, _> = parts.iter().map(|x| x.trim().parse::<f64>()).collect();
    match numbers.as_deref() {
        Ok([a, b]) if a.is_finite() && b.is_finite() => Ok([*a, *b]),
        _ => Err(format!(
            "expected {what} (two finite numbers, comma-separated)"
        )),
    }
}

fn check(value: f64, range: &RangeInclusive<f64>, what: &str) -> Result<(), String> {
    if range.contains(&value) {
        Ok(())
    } else {
        Err(format!(
            "{what} {value} is outside the valid range {}",
            closed(range)
        ))
    }
}

fn parse_weak_motor(s: &str) -> Result<WeakMotor, String> {
    let [motor, factor] = pair(s, "MOTOR,FACTOR")?;
    if !(motor.fract() == 0.0 && (1.0..=4.0).contains(&motor)) {
        return Err(format!(
            "motor {motor} does not exist: motors are 1, 2, 3, 4"
        ));
    }
    check(factor, &MOTOR_FACTOR_RANGE, "FACTOR")?;
    Ok(WeakMotor {
        index: motor as usize - 1,
        factor,
    })
}

fn parse_cg_offset(s: &str) -> Result<[f64; 2], String> {
    let xy = pair(s, "X,Y")?;
    for (v, axis) in xy.iter().zip(["X", "Y"]) {
        check(*v, &CG_OFFSET_RANGE_M, axis)?;
    }
    Ok(xy)
}

fn parse_payload(s: &str) -> Result<Payload, String> {
    let [mass_kg, release_s] = pair(s, "KG,T")?;
    check(mass_kg, &PAYLOAD_RANGE_KG, "KG")?;
    if release_s < 0.0 {
        return Err(format!("T {release_s} must be >= 0"));
    }
    Ok(Payload { mass_kg, release_s })
}

impl ModelErrorArgs {
    /// Puts the model error and the storm into `config`.
    pub fn apply(&self, config: &mut SimConfig) {
        config.model_error = ModelError {
            mass_scale: self.mass_scale.unwrap_or(1.0),
            weak_motor: self.weak_motor,
            cg_offset_m: self.cg_offset.unwrap_or([0.0; 2]),
            payload: self.payload_drop,
        };
        if self.gust_storm {
            config.gusts = Some(GustParams::storm());
        }
    }

    /// The summary's record of what was injected.
    pub fn summary(&self, config: &SimConfig) -> Value {
        let e = &config.model_error;
        json!({
            "mass_scale": e.mass_scale,
            "weak_motor": e.weak_motor.map(|m| json!({ "motor": m.index + 1, "factor": m.factor })),
            "cg_offset_m": e.cg_offset_m,
            "payload_drop": e.payload.map(|p| json!({ "mass_kg": p.mass_kg, "t_s": p.release_s })),
            "gust_storm": self.gust_storm,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_parsed_and_bad_ones_refused_with_the_reason() {
        let m = parse_weak_motor("2,0.8").unwrap();
        assert_eq!((m.index, m.factor), (1, 0.8));
        for (bad, reason) in [
            ("0,0.8", "does not exist"),
            ("5,0.8", "does not exist"),
            ("1.5,0.8", "does not exist"),
            ("1,0.3", "[0.5, 1]"),
            ("1,nan", "two finite numbers"),
            ("1", "two finite numbers"),
        ] {
            let e = parse_weak_motor(bad).unwrap_err();
            assert!(e.contains(reason), "{bad}: {e}");
        }
        assert_eq!(parse_cg_offset("-0.02,0.01"), Ok([-0.02, 0.01]));
        assert!(parse_cg_offset("0.1,0").unwrap_err().contains("X 0.1"));
        let p = parse_payload("0.3,20").unwrap();
        assert_eq!((p.mass_kg, p.release_s), (0.3, 20.0));
        assert!(parse_payload("2,20").unwrap_err().contains("KG 2"));
        assert!(parse_payload("0.3,-1").unwrap_err().contains("T -1"));
        assert!(parse_payload("0.3,inf").is_err());
    }
}
