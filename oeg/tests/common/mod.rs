//! What the crate's tests share: the shared real files, read when present.

use std::path::PathBuf;

/// The shared real file `name` (`../shared/data` beside the project, or `$OEG_SHARED_DATA`), or `None` with
/// the reason printed when it is absent: a user's clone does not have them, and the test then passes.
pub(crate) fn shared_file(name: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("OEG_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data"));
    let path = dir.join(name);
    if path.is_file() {
        Some(path)
    } else {
        println!(
            "skipped: {} is absent (the shared data set lives beside the project, not in it)",
            path.display()
        );
        None
    }
}
