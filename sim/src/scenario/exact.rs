//! Fixed-length arrays read at their exact length.
//!
//! serde reads `[f64; 2]` by taking two elements of a list, and the TOML reader drops whatever follows, so
//! `min_xy_m = [0, 0, 5]` would read as `[0, 0]` without a word. Every fixed-length field of the scenario and
//! sweep files is read through these functions instead (`#[serde(deserialize_with = "...")]`): a list of
//! another length is an error at its place in the file.

use serde::de::{Deserialize, Deserializer};

fn exact<T, E: serde::de::Error, const N: usize>(v: Vec<T>, what: &str) -> Result<[T; N], E> {
    let len = v.len();
    v.try_into()
        .map_err(|_| E::custom(format!("{what}expected a list of {N} values, got {len}")))
}

/// `[T; N]`, refusing a list of another length.
///
/// # Errors
/// A list of another length, or elements that do not read as `T`.
pub fn array<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    d: D,
) -> Result<[T; N], D::Error> {
    exact(Vec::<T>::deserialize(d)?, "")
}

/// `Option<[T; N]>` (give the field `#[serde(default)]` too).
///
/// # Errors
/// As [`array()`].
pub fn option<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    d: D,
) -> Result<Option<[T; N]>, D::Error> {
    Option::<Vec<T>>::deserialize(d)?
        .map(|v| exact(v, ""))
        .transpose()
}

/// `Vec<[T; N]>`, each entry at its exact length.
///
/// # Errors
/// As [`array()`], naming the entry (from 0).
pub fn each<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    d: D,
) -> Result<Vec<[T; N]>, D::Error> {
    Vec::<Vec<T>>::deserialize(d)?
        .into_iter()
        .enumerate()
        .map(|(k, v)| exact(v, &format!("entry {k}: ")))
        .collect()
}

#[cfg(test)]
mod tests {
    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Fields {
        #[serde(deserialize_with = "super::array")]
        xy: [f64; 2],
        #[serde(default, deserialize_with = "super::option")]
        maybe: Option<[u32; 2]>,
        #[serde(default, deserialize_with = "super::each")]
        points: Vec<[f64; 3]>,
    }

    fn read(text: &str) -> Result<Fields, String> {
        toml::from_str::<Fields>(text).map_err(|e| e.to_string())
    }

    #[test]
    fn lists_of_another_length_are_refused_at_their_place() {
        let ok = read("xy = [1.0, 2.0]\nmaybe = [3, 4]\npoints = [[1.0, 2.0, 3.0]]\n").expect("exact");
        assert_eq!(ok.xy, [1.0, 2.0]);
        assert_eq!(ok.maybe, Some([3, 4]));
        assert_eq!(ok.points, vec![[1.0, 2.0, 3.0]]);
        assert!(read("xy = [1.0, 2.0]\n").expect("defaults").maybe.is_none());
        for (text, expected) in [
            ("xy = [1.0, 2.0, 5.0]\n", "expected a list of 2 values, got 3"),
            ("xy = [1.0]\n", "expected a list of 2 values, got 1"),
            (
                "xy = [1.0, 2.0]\nmaybe = [1, 2, 3]\n",
                "expected a list of 2 values, got 3",
            ),
            (
                "xy = [1.0, 2.0]\npoints = [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0, 4.0]]\n",
                "entry 1: expected a list of 3 values, got 4",
            ),
        ] {
            let e = read(text).expect_err(text);
            assert!(e.contains(expected), "{text}: {e}");
            assert!(e.contains("line"), "{text}: the place is named: {e}");
        }
    }
}
