//! The backend on a thread of its own, so loop searches and optimisation never hold up a scan.
//!
//! The tracker hands each keyframe over a channel; the worker adds it, searches loops and
//! optimises in keyframe order, and publishes the corrected poses after each keyframe. What the
//! backend decides depends only on the keyframes and their order, never on timing, so a log
//! gives the same final map and trajectory on any machine; only how fresh the corrections are
//! that the scan path sees in the meantime depends on timing.

use crate::backend::{Backend, BackendStats};
use crate::config::SlamConfig;
use crate::keyframe::Keyframe;
use plumbline_core::geom::Pose2;
use std::sync::mpsc::{channel, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

/// What the worker has published so far.
#[derive(Clone, Debug, Default)]
pub struct Published {
    pub poses: Vec<Pose2>,
    /// Whether each processed keyframe kept its scan (see [`Keyframe::has_scan`]); a keyframe
    /// is thinned only when it is added, so the flag never changes once published.
    pub kept: Vec<bool>,
    pub stats: BackendStats,
}

pub struct Worker<const N: usize> {
    sender: Option<Sender<Keyframe>>,
    published: Arc<Mutex<Published>>,
    thread: Option<JoinHandle<Backend<N>>>,
}

impl<const N: usize> Worker<N> {
    pub fn spawn(config: SlamConfig) -> std::io::Result<Self> {
        let (sender, receiver) = channel::<Keyframe>();
        let published = Arc::new(Mutex::new(Published::default()));
        let shared = Arc::clone(&published);
        let thread = std::thread::Builder::new()
            .name("slam-backend".into())
            .spawn(move || {
                let mut backend = Backend::<N>::new(config);
                for keyframe in receiver {
                    backend.add_keyframe(keyframe);
                    if let Ok(mut p) = shared.lock() {
                        p.poses.clear();
                        p.poses.extend_from_slice(backend.poses());
                        p.kept
                            .push(backend.keyframes().last().is_some_and(Keyframe::has_scan));
                        p.stats = backend.stats();
                    }
                }
                backend.finish();
                backend
            })?;
        Ok(Self {
            sender: Some(sender),
            published,
            thread: Some(thread),
        })
    }

    /// Queues a keyframe; false if the worker has stopped (it panicked).
    pub fn send(&self, keyframe: Keyframe) -> bool {
        self.sender
            .as_ref()
            .is_some_and(|s| s.send(keyframe).is_ok())
    }

    /// The latest counts.
    pub fn stats(&self) -> BackendStats {
        self.published.lock().map(|p| p.stats).unwrap_or_default()
    }

    /// The corrected pose of keyframe `k` if published, else the newest published keyframe's
    /// index and pose (`None` before the first).
    pub fn pose_or_latest(&self, k: usize) -> Option<Result<Pose2, (usize, Pose2)>> {
        let p = self.published.lock().ok()?;
        match p.poses.get(k) {
            Some(&pose) => Some(Ok(pose)),
            None => p.poses.last().map(|&pose| Err((p.poses.len() - 1, pose))),
        }
    }

    /// Whether keyframe `k` kept its scan, `None` until the worker has processed it.
    pub fn kept(&self, k: usize) -> Option<bool> {
        self.published.lock().ok()?.kept.get(k).copied()
    }

    /// Waits for every queued keyframe to be processed and returns the backend.
    pub fn finish(mut self) -> Option<Backend<N>> {
        self.sender.take();
        self.thread.take().and_then(|t| t.join().ok())
    }
}
