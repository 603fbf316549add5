//! `POST /command`: the page's arm/land/kill buttons. A command is taken only with the view's
//! token in the `X-Plumbline-Token` header; it then waits in a bounded queue for the vehicle's
//! loop, which takes it at its next step.

use crate::stats::Counters;
use axum::http::{HeaderMap, StatusCode};
use plumbline_core::msgs::GroundCommand;
use std::sync::mpsc::{SyncSender, TrySendError};

/// The header that carries the token.
pub const TOKEN_HEADER: &str = "x-plumbline-token";

/// The command a button's name stands for.
fn parse(name: &str) -> Option<GroundCommand> {
    match name.trim() {
        "arm" => Some(GroundCommand::Arm),
        "land" => Some(GroundCommand::Land),
        "kill" => Some(GroundCommand::Terminate),
        _ => None,
    }
}

/// Compares in time independent of where the first difference is, so the token cannot be
/// guessed byte by byte from response times.
fn same_token(given: &[u8], expected: &[u8]) -> bool {
    given.len() == expected.len()
        && given
            .iter()
            .zip(expected)
            .fold(0u8, |acc, (a, b)| acc | (a ^ b))
            == 0
}

/// Decides one request: the status and a sentence for the page.
pub fn handle(
    token: Option<&str>,
    headers: &HeaderMap,
    body: &str,
    queue: &SyncSender<GroundCommand>,
    counters: &Counters,
) -> (StatusCode, String) {
    let Some(expected) = token else {
        Counters::bump(&counters.commands_refused);
        return (
            StatusCode::FORBIDDEN,
            "this view is read-only: start it with --view-token to allow commands".into(),
        );
    };
    let given = headers.get(TOKEN_HEADER).map(|v| v.as_bytes());
    if !given.is_some_and(|g| same_token(g, expected.as_bytes())) {
        Counters::bump(&counters.commands_refused);
        return (StatusCode::FORBIDDEN, "missing or wrong token".into());
    }
    let Some(command) = parse(body) else {
        Counters::bump(&counters.commands_invalid);
        return (
            StatusCode::BAD_REQUEST,
            "unknown command: send arm, land or kill".into(),
        );
    };
    match queue.try_send(command) {
        Ok(()) => {
            Counters::bump(&counters.commands_accepted);
            (StatusCode::ACCEPTED, format!("{} sent", body.trim()))
        }
        Err(TrySendError::Full(_)) => {
            Counters::bump(&counters.commands_queue_full);
            (
                StatusCode::SERVICE_UNAVAILABLE,
                "the vehicle has not taken the earlier commands yet: try again".into(),
            )
        }
        Err(TrySendError::Disconnected(_)) => {
            Counters::bump(&counters.commands_queue_full);
            (
                StatusCode::SERVICE_UNAVAILABLE,
                "the flight has ended".into(),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc::sync_channel;

    fn with_token(t: &str) -> HeaderMap {
        let mut h = HeaderMap::new();
        h.insert(TOKEN_HEADER, t.parse().unwrap());
        h
    }

    #[test]
    fn only_the_right_token_gets_a_command_through() {
        let (tx, rx) = sync_channel(4);
        let c = Counters::default();
        let none = HeaderMap::new();
        assert_eq!(
            handle(None, &with_token("s3"), "kill", &tx, &c).0,
            StatusCode::FORBIDDEN
        );
        assert_eq!(
            handle(Some("s3"), &none, "kill", &tx, &c).0,
            StatusCode::FORBIDDEN
        );
        assert_eq!(
            handle(Some("s3"), &with_token("s4"), "kill", &tx, &c).0,
            StatusCode::FORBIDDEN
        );
        assert_eq!(
            handle(Some("s3"), &with_token("s33"), "kill", &tx, &c).0,
            StatusCode::FORBIDDEN
        );
        assert!(rx.try_recv().is_err());
        assert_eq!(
            handle(Some("s3"), &with_token("s3"), "jump", &tx, &c).0,
            StatusCode::BAD_REQUEST
        );
        assert_eq!(
            handle(Some("s3"), &with_token("s3"), "kill\n", &tx, &c).0,
            StatusCode::ACCEPTED
        );
        assert_eq!(rx.try_recv(), Ok(GroundCommand::Terminate));
        let s = c.read();
        assert_eq!(
            (s.commands_refused, s.commands_invalid, s.commands_accepted),
            (4, 1, 1)
        );
    }

    #[test]
    fn a_full_queue_refuses_instead_of_waiting() {
        let (tx, rx) = sync_channel(2);
        let c = Counters::default();
        let h = with_token("t");
        for _ in 0..2 {
            assert_eq!(
                handle(Some("t"), &h, "land", &tx, &c).0,
                StatusCode::ACCEPTED
            );
        }
        assert_eq!(
            handle(Some("t"), &h, "arm", &tx, &c).0,
            StatusCode::SERVICE_UNAVAILABLE
        );
        assert_eq!(c.read().commands_queue_full, 1);
        assert_eq!(rx.try_recv(), Ok(GroundCommand::Land));
        drop(rx);
        assert_eq!(
            handle(Some("t"), &h, "arm", &tx, &c).0,
            StatusCode::SERVICE_UNAVAILABLE
        );
    }
}
