//! The parameter registry on a running autopilot: read and set its tuning by index.
//!
//! A set takes effect at the next step, without restarting anything: the loops keep their
//! integrals and filters (`Cascade::retune`), the supervisor and mission their timers; a new
//! timeout or threshold is compared with the time already elapsed, so shortening one can
//! trigger its failsafe at the next step, as it would have with that value from the start.
//! `HOLD_HEIGHT` is taken at the next arming, not by a flight in progress (a ground Takeoff
//! command moves the hold height in flight).

use super::Autopilot;
use crate::flight::params::{self, ParamError};
use crate::msgs::FlightMode;

impl Autopilot {
    /// Parameter `index` of the configuration in force.
    pub fn param(&self, index: usize) -> Option<f32> {
        params::get(&self.config, index)
    }

    /// Sets parameter `index` to `value` and returns the value now in force, or why it was
    /// refused (nothing changes then). See [`params`] for the checks and the module above for
    /// what a change does in flight.
    pub fn set_param(&mut self, index: usize, value: f32) -> Result<f32, ParamError> {
        let armed = !matches!(self.mode, FlightMode::Disarmed | FlightMode::Killed);
        let config = params::with(&self.config, index, value, armed)?;
        self.cascade
            .retune(config.cascade, config.mrac)
            .map_err(|_| ParamError::Inconsistent {
                rule: "the MRAC configuration must stay valid",
            })?;
        self.supervisor.retune(config.supervisor);
        self.mission.config = config.mission;
        self.config = config;
        Ok(value)
    }
}
