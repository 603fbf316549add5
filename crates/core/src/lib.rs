//! Plumbline's onboard algorithms.
//!
//! `#![no_std]` and heap-free so the same code runs on a companion computer and on a
//! Cortex-M4F-class flight controller. Every memory bound is a const generic or a caller
//! buffer, so `core::mem::size_of` tells an embedded user what a configuration costs.
//! Modules are listed lowest first; a module only uses modules above it.
#![no_std]
#![forbid(unsafe_code)]

mod fast_math;
pub mod geom;
pub mod msgs;
pub mod scan;
pub mod lidar;
pub mod matching;
pub mod estimate;
pub mod guidance;
pub mod control;
pub mod flight;
