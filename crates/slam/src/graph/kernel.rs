//! The robust kernel on loop edges: dynamic covariance scaling (DCS).
//!
//! Agarwal, Tipaldi, Spinello, Stachniss and Burgard, "Robust map optimization using dynamic
//! covariance scaling", ICRA 2013. Switchable constraints (Sünderhauf and Protzel, IROS 2012)
//! give each loop a switch variable s in [0, 1] that scales its information, with a prior
//! `Phi (1 - s)^2` pulling it on; DCS solves for the optimal switch in closed form,
//! `s = min(1, 2 Phi / (Phi + chi2))`, so it needs no extra variables and no extra fill in the
//! normal equations. A loop that agrees with the rest of the graph (chi2 <= Phi) keeps its full
//! information; one that disagrees by chi2 has its information scaled by `s^2`, which falls
//! like `1 / chi2^2`, so a wrong match far from the truth ends with a weight near zero and
//! the front end can count it as rejected.
//!
//! Scaling the information by `w = s^2` at each iteration is iteratively reweighted least
//! squares on the cost whose derivative in chi2 is w: `rho(chi2) = chi2` up to Phi and
//! `3 Phi - 4 Phi^2 / (Phi + chi2)` beyond (bounded by 3 Phi). The optimiser measures progress
//! with this rho, so its step acceptance agrees with the weights it solves with.

/// How loop edges are weighted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LoopKernel {
    /// Plain least squares: every loop is trusted fully (one false loop bends the map).
    None,
    /// Dynamic covariance scaling with threshold `phi` (in units of chi2). The paper found
    /// results insensitive to phi over a wide range; a correct 3-dof edge has chi2 about 3 on
    /// average and below 11 in 99 % of cases, so phi = 5 keeps most correct loops at full
    /// weight while a loop off by ten sigma keeps about 1 % of its information.
    Dcs { phi: f64 },
}

impl LoopKernel {
    /// The information scale `w` for an edge whose current error has squared length `chi2`.
    pub fn weight(self, chi2: f64) -> f64 {
        match self {
            LoopKernel::None => 1.0,
            LoopKernel::Dcs { phi } => {
                let s = (2.0 * phi / (phi + chi2)).min(1.0);
                s * s
            }
        }
    }

    /// The robust cost `rho(chi2)` the weights are the derivative of.
    pub fn cost(self, chi2: f64) -> f64 {
        match self {
            LoopKernel::Dcs { phi } if chi2 > phi => 3.0 * phi - 4.0 * phi * phi / (phi + chi2),
            _ => chi2,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn dcs_weight_is_the_derivative_of_its_cost(phi in 0.1..50.0f64, chi2 in 0.0..1e4f64) {
            let k = LoopKernel::Dcs { phi };
            let h = 1e-6 * (1.0 + chi2);
            let slope = (k.cost(chi2 + h) - k.cost((chi2 - h).max(0.0))) / (chi2 + h - (chi2 - h).max(0.0));
            prop_assert!((slope - k.weight(chi2)).abs() < 1e-4, "slope {slope} weight {}", k.weight(chi2));
            prop_assert!(k.cost(chi2) <= chi2 + 1e-9 && k.cost(chi2) <= 3.0 * phi);
        }
    }

    #[test]
    fn agreeing_loops_keep_full_weight_and_far_ones_lose_it() {
        let k = LoopKernel::Dcs { phi: 5.0 };
        assert_eq!(k.weight(3.0), 1.0);
        assert!(k.weight(100.0) < 0.01);
        assert_eq!(LoopKernel::None.weight(1e9), 1.0);
    }
}
