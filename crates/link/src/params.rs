//! The parameter protocol (PARAM_REQUEST_LIST, PARAM_REQUEST_READ, PARAM_SET) over whatever
//! holds the parameters: the caller implements [`ParameterStore`] (the autopilot's registry),
//! the link turns requests into PARAM_VALUE replies and refusals into PARAM_ERROR.

use plumbline_core::flight::params::ParamError;

/// MAVLink parameter names are at most 16 bytes.
pub const NAME_LEN: usize = 16;

/// Named, bounded parameters as the link serves them (the autopilot's registry,
/// `plumbline_core::flight::params`, through whatever owns the configuration). Names must be
/// unique in their first 16 bytes (MAVLink's limit): the link compares that much.
pub trait ParameterStore {
    fn count(&self) -> usize;
    /// The name of parameter `index` (< `count()`).
    fn name(&self, index: usize) -> Option<&str>;
    /// The value in force of parameter `index`.
    fn value(&self, index: usize) -> Option<f32>;
    /// Sets parameter `index`; returns the value now in force or why nothing changed.
    fn set(&mut self, index: usize, value: f32) -> Result<f32, ParamError>;

    /// The index of the parameter whose name matches `name` in its first 16 bytes.
    fn index_of(&self, name: &str) -> Option<usize> {
        let wanted = truncate(name);
        (0..self.count()).find(|&i| self.name(i).map(truncate) == Some(wanted))
    }
}

/// A name cut to MAVLink's 16 bytes (at a character boundary).
pub(crate) fn truncate(name: &str) -> &str {
    let mut end = name.len().min(NAME_LEN);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    &name[..end]
}

/// A parameter name as received (up to 16 bytes, not necessarily UTF-8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParamName {
    bytes: [u8; NAME_LEN],
}

impl ParamName {
    pub(crate) fn from_wire(raw: [u8; NAME_LEN]) -> Self {
        Self { bytes: raw }
    }

    /// The name up to its terminating NUL; `None` when it is not UTF-8.
    pub fn as_str(&self) -> Option<&str> {
        let len = self.bytes.iter().position(|&b| b == 0).unwrap_or(NAME_LEN);
        core::str::from_utf8(&self.bytes[..len]).ok()
    }

    pub(crate) fn raw(&self) -> [u8; NAME_LEN] {
        self.bytes
    }
}

/// Which parameter a PARAM_REQUEST_READ names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamRef {
    Index(u16),
    Name(ParamName),
}

/// A parameter request from the ground.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamRequest {
    /// Send every parameter.
    List,
    Read(ParamRef),
    Set {
        name: ParamName,
        value: f32,
    },
}

/// Admits at most `per_s` PARAM_SET per second on average with bursts of `burst`: a ground
/// station writing a few parameters is never slowed, a flood cannot keep the autopilot busy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RateLimit {
    per_s: f64,
    burst: f64,
    tokens: f64,
    last_s: Option<f64>,
}

impl RateLimit {
    pub(crate) fn new(per_s: f64, burst: f64) -> Self {
        Self {
            per_s,
            burst,
            tokens: burst,
            last_s: None,
        }
    }

    pub(crate) fn admit(&mut self, t_s: f64) -> bool {
        if let Some(last) = self.last_s {
            let elapsed = t_s - last;
            if elapsed.is_finite() && elapsed > 0.0 {
                self.tokens = (self.tokens + elapsed * self.per_s).min(self.burst);
            }
        }
        if t_s.is_finite() {
            self.last_s = Some(self.last_s.map_or(t_s, |l| l.max(t_s)));
        }
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_limit_admits_a_burst_then_the_rate() {
        let mut limit = RateLimit::new(10.0, 5.0);
        let burst = (0..20).filter(|_| limit.admit(0.0)).count();
        assert_eq!(burst, 5);
        // One second later ten more tokens, capped at the burst of five.
        assert_eq!((0..20).filter(|_| limit.admit(1.0)).count(), 5);
        // A tenth of a second later: one.
        assert_eq!((0..20).filter(|_| limit.admit(1.1)).count(), 1);
        // A clock going backwards earns nothing.
        assert_eq!((0..20).filter(|_| limit.admit(0.5)).count(), 0);
    }

    #[test]
    fn names_are_compared_in_their_first_16_bytes() {
        assert_eq!(truncate("POS_XY_P"), "POS_XY_P");
        assert_eq!(truncate("A_VERY_LONG_PARAMETER_NAME"), "A_VERY_LONG_PARA");
        assert_eq!(truncate("ééééééééé"), "éééééééé");
        let mut raw = [0u8; 16];
        raw[..4].copy_from_slice(b"GAIN");
        assert_eq!(ParamName::from_wire(raw).as_str(), Some("GAIN"));
        assert_eq!(ParamName::from_wire([0xff; 16]).as_str(), None);
    }
}
