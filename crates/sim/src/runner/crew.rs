//! An exploring vehicle's crew before the flight: the onboard stack and what its companion
//! computer is made of, put together into the pilot that flies them ([`ExploreCrew::board`]).

use super::companion::{CompanionLog, ExploreCompanion, Strategy};
use super::ground::GroundStation;
use super::onboard_link::{OnboardLink, WithCompanion, LARGE_SCAN_BEAMS, XV11_BEAMS};
use super::{Pilot, SetupError};
use plumbline_core::guidance::config::GuidanceConfig;
use plumbline_core::matching::local_map::MapCell;
use plumbline_explore::Explorer;
use plumbline_slam::{local_map_cells, Slam, SlamConfig};
use std::cell::RefCell;
use std::rc::Rc;

/// The onboard stack and its companion for one flight, before boarding: the companion's SLAM
/// borrows its local map's cells, so whoever flies the crew owns them ([`Self::local_map`])
/// for as long as the flight lasts.
pub struct ExploreCrew<const N: usize> {
    pub link: OnboardLink<N>,
    pub companion: CompanionParts,
}

/// What the companion is made of: its settings and the records it shares with the caller.
#[derive(Clone)]
pub struct CompanionParts {
    pub slam: SlamConfig,
    pub explorer: Rc<RefCell<Explorer>>,
    pub guidance: GuidanceConfig,
    pub strategy: Strategy,
    /// Whether the vehicle turns to the guidance's heading: only a lidar with a blind sector
    /// needs to face where it goes.
    pub turns: bool,
    /// The flight must be back on the ground by then, s.
    pub end_s: f64,
    pub log: Rc<RefCell<CompanionLog>>,
}

impl<const N: usize> ExploreCrew<N> {
    /// Cells for the SLAM's local map.
    pub fn local_map(&self) -> Vec<MapCell> {
        local_map_cells(&self.companion.slam)
    }

    /// The pilot: the stack with the companion on board, its SLAM on `cells` (run inline, so
    /// the flight is deterministic).
    pub fn board(self, cells: &mut [MapCell]) -> Result<Pilot<'_>, SetupError> {
        let parts = self.companion;
        let slam = Slam::new(parts.slam, cells, false)
            .map_err(|e| SetupError::Config(format!("companion SLAM: {}", e.0)))?;
        let companion = ExploreCompanion::new(
            slam,
            parts.explorer,
            parts.guidance,
            parts.strategy,
            parts.turns,
            parts.end_s,
            parts.log,
        )
        .map_err(SetupError::Config)?;
        Ok(Pilot::Onboard(Box::new(WithCompanion {
            link: self.link,
            companion: Box::new(companion),
        })))
    }
}

/// An exploring crew for either scan size.
pub enum AnyExploreCrew {
    Small(ExploreCrew<XV11_BEAMS>),
    Large(ExploreCrew<LARGE_SCAN_BEAMS>),
}

impl AnyExploreCrew {
    /// Cells for the SLAM's local map.
    pub fn local_map(&self) -> Vec<MapCell> {
        match self {
            AnyExploreCrew::Small(c) => c.local_map(),
            AnyExploreCrew::Large(c) => c.local_map(),
        }
    }

    /// Links a ground station to the onboard stack.
    pub fn link_ground(&mut self, station: Box<dyn GroundStation>) {
        match self {
            AnyExploreCrew::Small(c) => c.link.link_ground_station(station),
            AnyExploreCrew::Large(c) => c.link.link_ground_station(station),
        }
    }

    /// The pilot, its SLAM on `cells` (see [`ExploreCrew::board`]).
    pub fn board(self, cells: &mut [MapCell]) -> Result<Pilot<'_>, SetupError> {
        match self {
            AnyExploreCrew::Small(c) => c.board(cells),
            AnyExploreCrew::Large(c) => c.board(cells),
        }
    }
}
