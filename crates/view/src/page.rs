//! The page, compiled into the binary: no front-end build, nothing fetched from elsewhere.

/// The whole page: markup, style and script in one file.
pub const INDEX_HTML: &str = include_str!("page.html");
