//! Changing the cascade's gains while it flies (the parameter registry's sets).

use super::{Cascade, CascadeConfig};
use crate::control::mrac::{MracConfig, MracConfigError};

impl Cascade {
    /// New gains and limits for every loop (and the MRAC, when it flies), keeping their state:
    /// see [`crate::control::pid::Pid::retune`] and
    /// [`crate::control::mrac::Mrac::retune`]. An MRAC configuration it cannot fly is
    /// refused and nothing changes.
    pub fn retune(
        &mut self,
        config: CascadeConfig,
        mrac: MracConfig,
    ) -> Result<(), MracConfigError> {
        if let Some(m) = &mut self.mrac {
            m.retune(mrac)?;
        }
        let c = config;
        let loops = [
            (
                &mut self.position,
                [c.position_xy, c.position_xy, c.position_z],
            ),
            (
                &mut self.velocity,
                [c.velocity_xy, c.velocity_xy, c.velocity_z],
            ),
            (
                &mut self.attitude,
                [c.attitude_rp, c.attitude_rp, c.attitude_yaw],
            ),
            (&mut self.rate, [c.rate_rp, c.rate_rp, c.rate_yaw]),
        ];
        for (pids, configs) in loops {
            for (pid, pc) in pids.iter_mut().zip(configs) {
                pid.retune(pc);
            }
        }
        self.config = config;
        Ok(())
    }
}
