//! A LiPo pack: open-circuit voltage against state of charge, internal resistance, capacity, and
//! the low-voltage thresholds the onboard failsafes react to (seed 002: low-voltage landing).

use serde::{Deserialize, Serialize};

/// Per-cell open-circuit voltage at 0, 10, ..., 100 % charge: a typical LiPo discharge curve
/// (steep below 10 %, a plateau around 3.8 V, rising to 4.2 V full).
const CELL_OCV_V: [f64; 11] = [
    3.27, 3.61, 3.69, 3.73, 3.77, 3.79, 3.82, 3.87, 3.92, 4.02, 4.20,
];

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BatteryParams {
    pub cells: u32,
    pub capacity_ah: f64,
    /// Whole-pack internal resistance plus wiring, ohm.
    pub resistance_ohm: f64,
    /// Loaded cell voltage below which the pack counts as low (land soon), V.
    pub low_cell_v: f64,
    /// Loaded cell voltage below which the pack counts as critical (land now), V.
    pub critical_cell_v: f64,
    /// Charge at the start of a flight, 0..1.
    pub initial_soc: f64,
}

impl BatteryParams {
    /// A 3S pack of the given capacity and resistance, full at take-off.
    pub fn three_cell(capacity_ah: f64, resistance_ohm: f64) -> Self {
        Self {
            cells: 3,
            capacity_ah,
            resistance_ohm,
            low_cell_v: 3.5,
            critical_cell_v: 3.3,
            initial_soc: 1.0,
        }
    }
}

/// The pack during a flight.
#[derive(Clone, Debug)]
pub struct Battery {
    params: BatteryParams,
    /// State of charge, 0..1.
    pub soc: f64,
    /// Terminal voltage under the last load, V.
    pub voltage_v: f64,
    pub current_a: f64,
    /// Energy drawn from the cells so far (terminal energy plus internal loss), Wh.
    pub energy_wh: f64,
    /// Worked out once, because a draw runs at every physics step and a division costs about as
    /// much as the rest of it: 1/(2R), state of charge per ampere-second, and the two
    /// thresholds as pack voltages.
    inv_2r: f64,
    soc_per_as: f64,
    low_v: f64,
    critical_v: f64,
}

/// Pack state after a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BatteryLevel {
    Ok,
    Low,
    Critical,
    /// The cells cannot deliver the demanded power (voltage collapse).
    Exhausted,
}

impl Battery {
    pub fn new(params: BatteryParams) -> Self {
        let soc = params.initial_soc.clamp(0.0, 1.0);
        let cells = params.cells as f64;
        let mut b = Self {
            inv_2r: 0.5 / params.resistance_ohm,
            soc_per_as: 1.0 / (3600.0 * params.capacity_ah),
            low_v: params.low_cell_v * cells,
            critical_v: params.critical_cell_v * cells,
            params,
            soc,
            voltage_v: 0.0,
            current_a: 0.0,
            energy_wh: 0.0,
        };
        b.voltage_v = b.open_circuit_v();
        b
    }

    /// Open-circuit pack voltage at the present charge (linear between table points).
    pub fn open_circuit_v(&self) -> f64 {
        let x = self.soc.clamp(0.0, 1.0) * 10.0;
        // x is non-negative, so truncation is floor (and needs no libm call); through `u32`
        // because SSE2 has no conversion to an unsigned 64-bit integer (see `nearby::sector_of`).
        let i = (x as u32 as usize).min(9);
        let f = x - i as f64;
        let cell = CELL_OCV_V[i] + (CELL_OCV_V[i + 1] - CELL_OCV_V[i]) * f;
        cell * self.params.cells as f64
    }

    /// Draws `power_w` at the terminals for `dt_s`: solves V = OCV - I R with P = V I for the
    /// current (the root with the smaller current), then discharges.
    pub fn draw(&mut self, power_w: f64, dt_s: f64) -> BatteryLevel {
        let ocv = self.open_circuit_v();
        let r = self.params.resistance_ohm;
        let p = power_w.max(0.0);
        let disc = ocv * ocv - 4.0 * r * p;
        let (current, exhausted) = if r == 0.0 {
            (p / ocv, false)
        } else if disc < 0.0 || self.soc <= 0.0 {
            (ocv / (2.0 * r), true)
        } else {
            ((ocv - disc.sqrt()) * self.inv_2r, false)
        };
        self.current_a = current;
        self.voltage_v = ocv - current * r;
        self.soc = (self.soc - current * dt_s * self.soc_per_as).max(0.0);
        self.energy_wh += ocv * current * dt_s * (1.0 / 3600.0);
        if exhausted {
            BatteryLevel::Exhausted
        } else if self.voltage_v < self.critical_v {
            BatteryLevel::Critical
        } else if self.voltage_v < self.low_v {
            BatteryLevel::Low
        } else {
            BatteryLevel::Ok
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discharge_is_monotone_sags_under_load_and_ends_low() {
        let mut b = Battery::new(BatteryParams::three_cell(2.2, 0.025));
        assert!((b.voltage_v - 12.6).abs() < 1e-9, "full 3S pack is 12.6 V");
        let mut last_soc = b.soc;
        let mut last_ocv = b.open_circuit_v();
        let mut low_seen = false;
        for _ in 0..20_000 {
            let level = b.draw(130.0, 0.1);
            let ocv = b.open_circuit_v();
            assert!(b.soc <= last_soc && ocv <= last_ocv + 1e-12);
            assert!(
                b.voltage_v < ocv,
                "terminal voltage sags below open circuit under load"
            );
            last_soc = b.soc;
            last_ocv = ocv;
            if level != BatteryLevel::Ok {
                low_seen = true;
                break;
            }
        }
        assert!(low_seen, "a 130 W load must reach the low threshold");
        // 2.2 Ah at ~11.4 V mean is ~25 Wh; low arrives after most of it is used.
        assert!(
            b.energy_wh > 15.0 && b.energy_wh < 26.0,
            "energy {}",
            b.energy_wh
        );
    }

    #[test]
    fn impossible_power_is_reported_not_nan() {
        let mut b = Battery::new(BatteryParams::three_cell(2.2, 0.5));
        assert_eq!(b.draw(1.0e5, 0.001), BatteryLevel::Exhausted);
        assert!(b.voltage_v.is_finite() && b.current_a.is_finite());
    }
}
