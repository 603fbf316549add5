//! `--view ADDR [--view-token T]`: the live web view, shared by the commands that fly.

use crate::report::CliError;
use clap::Args;
use plumbline_view::{View, ViewConfig};
use serde_json::{json, Value};
use std::net::SocketAddr;

#[derive(Args, Debug, Default)]
pub struct ViewArgs {
    /// Serve a live web view of the flight at ADDR, e.g. 127.0.0.1:8080 (port 0 picks a free
    /// one; the address is printed). Keep it on 127.0.0.1 unless others must watch: the view
    /// has no encryption.
    #[arg(long, value_name = "ADDR")]
    pub view: Option<SocketAddr>,
    /// Let the view's page arm, land and kill, with this token typed into the page (or given
    /// as #token=... in its address). Without it the view is read-only.
    #[arg(long, value_name = "TOKEN", requires = "view")]
    pub view_token: Option<String>,
}

impl ViewArgs {
    /// Starts the view when asked for, and says where it is on stderr.
    pub fn start(&self) -> Result<Option<View>, CliError> {
        let Some(addr) = self.view else {
            return Ok(None);
        };
        let view = View::start(ViewConfig::new(addr, self.view_token.clone()))
            .map_err(|e| CliError(e.to_string()))?;
        let access = if self.view_token.is_some() {
            "arm/land/kill with the token"
        } else {
            "read-only"
        };
        eprintln!("view: http://{}/ ({access})", view.local_addr());
        Ok(Some(view))
    }
}

/// The view's counters for the run's summary.
pub fn summary(view: &View) -> Value {
    json!({ "address": view.local_addr().to_string(), "stats": view.stats() })
}
