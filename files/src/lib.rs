//! The framing, the bounded reads and the atomic writes that the OEG project's files share: the map file
//! (`.oeg`) and the sensor log (`.oeglog`) are framed alike ([`container`]), every input is read within a
//! bound the caller gives ([`read_bounded`], [`read_text`]), and every output is written whole or not at all
//! ([`AtomicFile`], [`write_atomically`]). The map crate, the simulator and the testbed call these; none of
//! them is part of the map's own API.

mod atomic;
pub mod container;
mod error;
mod hash;
mod read;

pub use atomic::{AtomicFile, output_target, stale_owners, unique_suffix, write_atomically};
pub use container::{
    ContainerPrefix, FramedWriter, check_container_checksum, container_prefix_bytes, read_container_prefix,
    seal_container,
};
pub use error::{FileError, Result};
pub use hash::{Fnv1a64, fnv1a64};
pub use read::{ByteReader, MAX_TEXT_INPUT_BYTES, read_bounded, read_text};

/// The rotation of a quaternion `(w, x, y, z)` read from a file, or `None` when it is zero or not finite.
///
/// The components are scaled by the largest of them before normalising, so a finite quaternion of any
/// magnitude (1e200 as well as 1e-200) keeps its rotation: a plain norm overflows to infinity there and the
/// rotation is silently lost.
#[inline]
pub fn unit_quaternion(w: f64, x: f64, y: f64, z: f64) -> Option<nalgebra::UnitQuaternion<f64>> {
    if ![w, x, y, z].iter().all(|v| v.is_finite()) {
        return None;
    }
    let scale = [w, x, y, z].iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if scale == 0.0 {
        return None;
    }
    let q = nalgebra::Quaternion::new(w / scale, x / scale, y / scale, z / scale);
    Some(nalgebra::UnitQuaternion::from_quaternion(q))
}

#[cfg(test)]
#[allow(clippy::disallowed_methods, reason = "tests write their inputs directly")]
mod tests {
    use super::*;
    use crate::read::ByteReader;
    use std::path::{Path, PathBuf};

    #[test]
    fn text_inputs_over_the_limit_are_refused_before_they_are_read() {
        let dir = scratch_dir("bounded");
        let path = dir.join("big.toml");
        std::fs::write(&path, vec![b'#'; 100]).expect("write");
        assert_eq!(read_bounded(&path, 100).expect("fits").len(), 100);
        let e = read_bounded(&path, 99).expect_err("over").to_string();
        assert!(
            e.contains("big.toml") && e.contains("100 bytes, over the limit of 99"),
            "{e}"
        );
        // A device of endless bytes stops at the limit, not at the end of memory.
        let e = read_bounded(Path::new("/dev/zero"), 1 << 20)
            .expect_err("endless")
            .to_string();
        assert!(e.contains("/dev/zero") && e.contains("over the limit"), "{e}");
        std::fs::write(&path, b"name = \"\xff\"").expect("write");
        let e = read_text(&path).expect_err("not UTF-8").to_string();
        assert!(e.contains("byte 8: not UTF-8"), "{e}");
        assert!(
            read_text(&dir)
                .expect_err("a folder")
                .to_string()
                .contains("folder")
        );
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn fnv1a64_matches_the_reference_values() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn atomic_writes_leave_no_temporary_file() {
        let dir = std::env::temp_dir().join(format!("oeg-io-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("x.bin");
        write_atomically(&path, b"hello").expect("written");
        assert_eq!(std::fs::read(&path).expect("read"), b"hello");
        let names: Vec<_> = std::fs::read_dir(&dir)
            .expect("dir")
            .map(|e| e.expect("entry").file_name())
            .collect();
        assert_eq!(names.len(), 1, "{names:?}");
        let err = write_atomically(&dir.join("missing/x.bin"), b"x").expect_err("no such folder");
        assert!(err.to_string().contains("missing"), "{err}");
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    fn scratch_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("oeg-io-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    #[test]
    fn writing_over_a_fifo_or_a_link_to_one_is_refused_and_leaves_it_a_fifo() {
        use std::os::unix::fs::FileTypeExt;
        let dir = scratch_dir("fifo");
        let fifo = dir.join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !made.is_ok_and(|s| s.success()) {
            println!("skipped: `mkfifo` is not available here");
            return;
        }
        let link = dir.join("link");
        std::os::unix::fs::symlink(&fifo, &link).expect("symlink");
        for path in [&fifo, &link] {
            let err = write_atomically(path, b"x").expect_err("a FIFO is not a regular file");
            assert!(err.to_string().contains("FIFO"), "{err}");
            assert!(
                std::fs::metadata(&fifo)
                    .expect("still there")
                    .file_type()
                    .is_fifo()
            );
        }
        assert!(
            std::fs::symlink_metadata(&link)
                .expect("link")
                .file_type()
                .is_symlink()
        );
        let err = write_atomically(&dir, b"x").expect_err("a folder");
        assert!(err.to_string().contains("folder"), "{err}");
        assert_eq!(
            std::fs::read_dir(&dir).expect("dir").count(),
            2,
            "no temporary left"
        );
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn a_link_to_a_regular_file_is_followed_and_kept() {
        let dir = scratch_dir("link");
        let target = dir.join("real.txt");
        std::fs::write(&target, b"old").expect("write");
        let link = dir.join("link.txt");
        std::os::unix::fs::symlink(&target, &link).expect("symlink");
        write_atomically(&link, b"new").expect("written through the link");
        assert_eq!(std::fs::read(&target).expect("read"), b"new");
        assert!(
            std::fs::symlink_metadata(&link)
                .expect("link")
                .file_type()
                .is_symlink()
        );
        let dangling = dir.join("dangling");
        std::os::unix::fs::symlink(dir.join("nowhere"), &dangling).expect("symlink");
        assert!(write_atomically(&dangling, b"x").is_err());
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn temporary_files_of_killed_writers_are_removed_and_live_ones_kept() {
        let dir = scratch_dir("stale");
        let path = dir.join("map.oeg");
        // No process has pid 4294967295; this process is alive.
        let stale = dir.join("map.oeg.4294967295.0.tmp");
        let live = dir.join(format!("map.oeg.{}.99.tmp", std::process::id()));
        let other = dir.join("notes.4294967295.0.tmp");
        for p in [&stale, &live, &other] {
            std::fs::write(p, b"partial").expect("write");
        }
        write_atomically(&path, b"map").expect("written");
        if Path::new("/proc/self").exists() {
            assert!(!stale.exists(), "a dead writer's temporary file is removed");
        }
        assert!(
            live.exists() && other.exists(),
            "only this path's dead temporaries go"
        );
        std::fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn huge_and_tiny_quaternions_keep_their_rotation() {
        let expected =
            nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(0.5, 0.5, 0.5, 0.5));
        for scale in [1e200, 1e-200, 1.0, f64::MAX / 2.0] {
            let q = unit_quaternion(0.5 * scale, 0.5 * scale, 0.5 * scale, 0.5 * scale).expect("a rotation");
            assert!(q.angle_to(&expected) < 1e-12, "scale {scale}: {q:?}");
        }
        assert!(unit_quaternion(0.0, 0.0, 0.0, 0.0).is_none());
        assert!(unit_quaternion(f64::INFINITY, 0.0, 0.0, 0.0).is_none());
        assert!(unit_quaternion(f64::NAN, 1.0, 0.0, 0.0).is_none());
    }

    #[test]
    fn truncation_errors_name_the_file_and_offset() {
        let path = Path::new("some/file.bin");
        let mut r = ByteReader::new(path, &[1, 0, 0]);
        let err = r.u32("the node count").expect_err("truncated");
        let text = err.to_string();
        assert!(
            text.contains("some/file.bin") && text.contains("byte 0") && text.contains("node count"),
            "{text}"
        );
    }
}
