//! PNG plotting shared by the subcommands.
//!
//! Text needs a font; plotters' `ab_glyph` backend takes one at run time. We register DejaVu Sans
//! from the system (Debian's fonts-dejavu-core, present on the project's machines). Without it
//! plots are still drawn, only without captions and tick labels.

use std::sync::OnceLock;

const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
];

/// True when a font was registered, so callers may draw text.
pub fn fonts_available() -> bool {
    static FONT: OnceLock<bool> = OnceLock::new();
    *FONT.get_or_init(|| {
        FONT_PATHS.iter().any(|path| {
            let Ok(bytes) = std::fs::read(path) else { return false };
            let leaked: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, leaked)
                .is_ok()
        })
    })
}
