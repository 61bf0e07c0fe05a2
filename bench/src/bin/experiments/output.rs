//! Where the experiments write: the output folder, JSON files, and plots whose failures
//! (no TrueType font) are collected rather than fatal.

use std::path::{Path, PathBuf};

use strata_systems::report::plot::{self, Axes};

use crate::BoxError;

/// The run's settings and what it has written so far.
pub struct Ctx {
    /// Folder of the JSON files and plots.
    pub out: PathBuf,
    /// Fewer sample counts and realizations (`--quick`).
    pub quick: bool,
    /// Messages of the plots that could not be drawn.
    pub plot_errors: Vec<String>,
}

impl Ctx {
    /// Runs a plot; failures (no font) are collected, not fatal. Returns the file name.
    pub fn plot(
        &mut self,
        name: &str,
        f: impl FnOnce(&Path) -> Result<(), plot::PlotError>,
    ) -> String {
        let path = self.out.join(name);
        if let Err(e) = f(&path) {
            self.plot_errors.push(e.to_string());
        }
        name.to_string()
    }

    /// [`plot`](Self::plot), returning the `(file, caption)` of a section's figure.
    pub fn figure(
        &mut self,
        name: &str,
        caption: impl Into<String>,
        f: impl FnOnce(&Path) -> Result<(), plot::PlotError>,
    ) -> (String, String) {
        (self.plot(name, f), caption.into())
    }

    /// Writes `value` as pretty JSON to `name` in the output folder.
    pub fn json(&self, name: &str, value: &serde_json::Value) -> Result<(), BoxError> {
        let text = serde_json::to_string_pretty(value)?;
        strata_engine::io::write_atomically(&self.out.join(name), |w| {
            std::io::Write::write_all(w, text.as_bytes())
        })?;
        Ok(())
    }
}

/// Axes of a discrepancy-against-N plot, log-log.
pub fn discrepancy_axes(title: String) -> Axes {
    Axes {
        title,
        x_label: "log10 N".into(),
        y_label: "log10 discrepancy".into(),
        log_x: true,
        log_y: true,
        ..Default::default()
    }
}
