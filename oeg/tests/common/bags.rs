//! What the bag tests share: a scratch folder for a bag and a transform to write into it.

use std::path::PathBuf;

use nalgebra::Isometry3;
use oeg::BagTransform;

/// An empty scratch folder for the bag `name` of the test file `file`, unique to this process.
pub(crate) fn scratch(file: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("oeg-{file}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The transform `parent` -> `child` at `stamp_ns`.
pub(crate) fn transform(parent: &str, child: &str, stamp_ns: i64, t: Isometry3<f64>) -> BagTransform {
    BagTransform {
        parent: parent.into(),
        child: child.into(),
        stamp_ns,
        transform: t,
    }
}
