//! Electrical power of the vehicle, split the way seed 000 Fig. 12 splits it: motors, ESCs and
//! the flight controller (avionics).
//!
//! Each rotor's shaft power is its aerodynamic torque times speed, k_M Ω³, plus the power that
//! spins it up, I_r Ω Ω̇ (no regeneration when it slows: ordinary ESC firmware does not brake
//! into the pack). The motor draws shaft power / efficiency; the ESC loses a fraction of what it
//! passes (FET switching and conduction) plus its regulator's quiescent draw.

use crate::vehicle::VehicleParams;

/// Power of each part at one instant, W.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PowerSplit {
    pub motors_w: f64,
    pub escs_w: f64,
    pub avionics_w: f64,
}

impl PowerSplit {
    pub fn total_w(&self) -> f64 {
        self.motors_w + self.escs_w + self.avionics_w
    }
}

/// Power for rotor speeds `omega` (rad/s) and their rates `omega_dot` (rad/s²).
pub fn power(p: &VehicleParams, omega: &[f64; 4], omega_dot: &[f64; 4]) -> PowerSplit {
    let shaft: f64 = omega
        .iter()
        .zip(omega_dot)
        .map(|(&w, &wd)| (p.moment_coeff * w * w * w + p.rotor_inertia_kgm2 * w * wd).max(0.0))
        .sum();
    let motors_w = shaft / p.motor_efficiency;
    PowerSplit {
        motors_w,
        escs_w: motors_w * p.esc_loss_fraction + 4.0 * p.esc_quiescent_w,
        avionics_w: p.avionics_w,
    }
}

/// Energy per part accumulated over a flight, Wh.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyTally {
    pub motors_wh: f64,
    pub escs_wh: f64,
    pub avionics_wh: f64,
}

impl EnergyTally {
    /// Adds `dt_s` at power `s` (one division for the three parts: this runs every step).
    pub fn add(&mut self, s: &PowerSplit, dt_s: f64) {
        let hours = dt_s / 3600.0;
        self.motors_wh += s.motors_w * hours;
        self.escs_wh += s.escs_w * hours;
        self.avionics_wh += s.avionics_w * hours;
    }

    pub fn total_wh(&self) -> f64 {
        self.motors_wh + self.escs_wh + self.avionics_wh
    }

    /// Fractions (motors, escs, avionics) of the total.
    pub fn fractions(&self) -> [f64; 3] {
        let t = self.total_wh();
        if t <= 0.0 {
            return [0.0; 3];
        }
        [self.motors_wh / t, self.escs_wh / t, self.avionics_wh / t]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hover_split_has_the_shape_of_seed_000_fig_12() {
        for p in [VehicleParams::f450(), VehicleParams::pelican()] {
            let w = p.hover_rotor_speed();
            let s = power(&p, &[w; 4], &[0.0; 4]);
            let mut tally = EnergyTally::default();
            tally.add(&s, 60.0);
            let [m, e, a] = tally.fractions();
            assert!((0.93..0.97).contains(&m), "{}: motors {m}", p.name);
            assert!((0.03..0.05).contains(&e), "{}: escs {e}", p.name);
            assert!((0.005..0.02).contains(&a), "{}: avionics {a}", p.name);
            assert!(
                (80.0..250.0).contains(&s.total_w()),
                "{}: hover power {}",
                p.name,
                s.total_w()
            );
        }
    }

    #[test]
    fn spinning_up_costs_power_and_slowing_down_returns_none() {
        let p = VehicleParams::f450();
        let w = p.hover_rotor_speed();
        let steady = power(&p, &[w; 4], &[0.0; 4]).motors_w;
        assert!(power(&p, &[w; 4], &[2000.0; 4]).motors_w > steady);
        assert_eq!(power(&p, &[w; 4], &[-1.0e6; 4]).motors_w, 0.0);
    }
}
