//! The transform tree of a bag, as tf2 keeps it: each frame has one parent, from `/tf_static` (valid at every
//! time) or from `/tf` and odometry (stamped samples, interpolated between: linear in translation, spherical in
//! rotation). A lookup walks both frames up to their closest common ancestor, so only the edges between them
//! need a transform at the stamp.

use std::collections::HashMap;

use nalgebra::Isometry3;

/// How a frame hangs from its parent.
enum Link {
    Static(Isometry3<f64>),
    /// Samples `(stamp_ns, parent_from_child)`, sorted by stamp once the bag is read.
    Stamped(Vec<(i64, Isometry3<f64>)>),
}

struct Edge {
    parent: usize,
    link: Link,
}

/// Every frame the bag's transforms name, and the edge from each to its parent.
#[derive(Default)]
pub(crate) struct TfTree {
    names: Vec<String>,
    index: HashMap<String, usize>,
    /// By child frame.
    edges: HashMap<usize, Edge>,
}

impl TfTree {
    fn frame(&mut self, name: &str) -> usize {
        if let Some(&k) = self.index.get(name) {
            return k;
        }
        self.names.push(name.to_string());
        self.index.insert(name.to_string(), self.names.len() - 1);
        self.names.len() - 1
    }

    /// Whether the tree names `frame`.
    pub(crate) fn has_frame(&self, frame: &str) -> bool {
        self.index.contains_key(frame)
    }

    /// The frames' names, sorted, for a message.
    pub(crate) fn frames(&self) -> String {
        let mut names: Vec<&str> = self.names.iter().map(String::as_str).collect();
        names.sort_unstable();
        names
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Adds `parent_from_child`, static or at `stamp_ns`.
    ///
    /// # Errors
    /// A frame given a second parent, a frame that is both static and stamped, or an edge that would close a
    /// cycle, in words.
    pub(crate) fn add(
        &mut self,
        parent: &str,
        child: &str,
        stamp_ns: Option<i64>,
        parent_from_child: Isometry3<f64>,
    ) -> Result<(), String> {
        if parent == child {
            return Err(format!("frame `{child}` is given itself as its parent"));
        }
        let (p, c) = (self.frame(parent), self.frame(child));
        // A cycle: the child is already an ancestor of the parent.
        let mut up = Some(p);
        for _ in 0..=self.names.len() {
            match up {
                Some(f) if f == c => {
                    return Err(format!(
                        "`{parent}` -> `{child}` closes a cycle in the transform tree (`{child}` is already an \
                         ancestor of `{parent}`)"
                    ));
                }
                Some(f) => up = self.edges.get(&f).map(|e| e.parent),
                None => break,
            }
        }
        match (self.edges.get_mut(&c), stamp_ns) {
            (None, _) => {
                let link = match stamp_ns {
                    Some(t) => Link::Stamped(vec![(t, parent_from_child)]),
                    None => Link::Static(parent_from_child),
                };
                self.edges.insert(c, Edge { parent: p, link });
                Ok(())
            }
            (Some(e), _) if e.parent != p => Err(format!(
                "frame `{child}` has two parents, `{}` and `{parent}`",
                self.names[e.parent]
            )),
            (Some(e), Some(t)) => match &mut e.link {
                Link::Stamped(samples) => {
                    samples.push((t, parent_from_child));
                    Ok(())
                }
                Link::Static(_) => Err(format!(
                    "`{parent}` -> `{child}` comes on /tf_static and stamped (on /tf or as odometry)"
                )),
            },
            (Some(e), None) => {
                if let Link::Stamped(_) = e.link {
                    return Err(format!(
                        "`{parent}` -> `{child}` comes stamped (on /tf or as odometry) and on /tf_static"
                    ));
                }
                // A static transform sent again (latched on every recording's start) replaces the last.
                e.link = Link::Static(parent_from_child);
                Ok(())
            }
        }
    }

    /// Sorts each frame's samples by stamp (a later sample of an equal stamp wins, as in tf2's buffer).
    pub(crate) fn finish(&mut self) {
        for e in self.edges.values_mut() {
            if let Link::Stamped(samples) = &mut e.link {
                samples.sort_by_key(|s| s.0);
                let mut kept: Vec<(i64, Isometry3<f64>)> = Vec::with_capacity(samples.len());
                for s in samples.drain(..) {
                    match kept.last_mut() {
                        Some(last) if last.0 == s.0 => *last = s,
                        _ => kept.push(s),
                    }
                }
                *samples = kept;
            }
        }
    }

    /// `target_from_source` at `stamp_ns`: each stamped edge between the two frames interpolated at the stamp,
    /// or taken from its nearest sample within `tolerance_ns` outside the samples' span.
    ///
    /// # Errors
    /// Why not, in words: an unknown frame, frames in two trees, or an edge with no transform at the stamp.
    pub(crate) fn lookup(
        &self,
        target: &str,
        source: &str,
        stamp_ns: i64,
        tolerance_ns: i64,
    ) -> Result<Isometry3<f64>, String> {
        let frame = |name: &str| {
            self.index
                .get(name)
                .copied()
                .ok_or_else(|| format!("no transform names frame `{name}`"))
        };
        let (t, s) = (frame(target)?, frame(source)?);
        // The source's ancestors, each with ancestor_from_source.
        let mut ancestors = vec![(s, Isometry3::identity())];
        loop {
            let (f, below) = ancestors[ancestors.len() - 1];
            let Some(e) = self.edges.get(&f) else { break };
            ancestors.push((e.parent, self.at(f, e, stamp_ns, tolerance_ns)? * below));
        }
        let mut up = (t, Isometry3::identity());
        loop {
            if let Some((_, anc_from_source)) = ancestors.iter().find(|(f, _)| *f == up.0) {
                return Ok(up.1.inverse() * anc_from_source);
            }
            let Some(e) = self.edges.get(&up.0) else {
                return Err(format!(
                    "frames `{target}` and `{source}` are not connected (their trees' roots are `{}` and `{}`)",
                    self.names[up.0],
                    self.names[ancestors[ancestors.len() - 1].0]
                ));
            };
            up = (e.parent, self.at(up.0, e, stamp_ns, tolerance_ns)? * up.1);
        }
    }

    /// `parent_from_child` of the edge `e` above frame `child` at `stamp_ns`.
    fn at(&self, child: usize, e: &Edge, stamp_ns: i64, tolerance_ns: i64) -> Result<Isometry3<f64>, String> {
        let samples = match &e.link {
            Link::Static(t) => return Ok(*t),
            Link::Stamped(samples) => samples,
        };
        let k = samples.partition_point(|s| s.0 < stamp_ns);
        let child = &self.names[child];
        let out_of_range = |gap_ns: i64, side: &str| {
            format!(
                "the transform `{}` -> `{child}` is {:.3} s {side} the stamp (tolerance {:.3} s)",
                self.names[e.parent],
                gap_ns as f64 * 1e-9,
                tolerance_ns as f64 * 1e-9
            )
        };
        match (k.checked_sub(1).map(|j| samples[j]), samples.get(k)) {
            (_, Some(after)) if after.0 == stamp_ns => Ok(after.1),
            (Some(before), Some(after)) => {
                let f = (stamp_ns - before.0) as f64 / (after.0 - before.0) as f64;
                Ok(before.1.lerp_slerp(&after.1, f))
            }
            (Some(before), None) if stamp_ns - before.0 <= tolerance_ns => Ok(before.1),
            (Some(before), None) => Err(out_of_range(stamp_ns - before.0, "older than")),
            (None, Some(after)) if after.0 - stamp_ns <= tolerance_ns => Ok(after.1),
            (None, Some(after)) => Err(out_of_range(after.0 - stamp_ns, "newer than")),
            (None, None) => Err(format!("no transform `{}` -> `{child}`", self.names[e.parent])),
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Point3, Vector3};

    use super::*;

    fn shift(x: f64, y: f64) -> Isometry3<f64> {
        Isometry3::translation(x, y, 0.0)
    }

    #[test]
    fn a_lookup_interpolates_stamped_edges_and_composes_through_the_tree() {
        let mut tf = TfTree::default();
        tf.add("map", "odom", None, shift(10.0, 0.0)).expect("edge");
        tf.add("odom", "base_link", Some(0), shift(0.0, 0.0))
            .expect("edge");
        tf.add("odom", "base_link", Some(1_000_000_000), shift(2.0, 0.0))
            .expect("edge");
        tf.add("base_link", "lidar", None, shift(0.0, 1.0)).expect("edge");
        tf.finish();
        let half = tf.lookup("map", "lidar", 500_000_000, 0).expect("found");
        assert!((half * Point3::origin() - Point3::new(11.0, 1.0, 0.0)).norm() < 1e-12);
        // The other way round, and between two frames below the root.
        let back = tf.lookup("lidar", "map", 500_000_000, 0).expect("found");
        assert!((back * half).translation.vector.norm() < 1e-12);
        let sibling = tf
            .lookup("base_link", "lidar", 123, 0)
            .expect("static edges only");
        assert_eq!(sibling.translation.vector, Vector3::new(0.0, 1.0, 0.0));
        // Beyond the samples: within the tolerance, the nearest; beyond it, refused with the gap.
        assert!(tf.lookup("map", "lidar", 1_050_000_000, 100_000_000).is_ok());
        let e = tf
            .lookup("map", "lidar", 2_000_000_000, 100_000_000)
            .expect_err("refused");
        assert!(e.contains("1.000 s older"), "{e}");
        assert!(
            tf.lookup("map", "camera", 0, 0)
                .expect_err("refused")
                .contains("`camera`")
        );
    }

    #[test]
    fn cycles_second_parents_and_mixed_edges_are_refused() {
        let mut tf = TfTree::default();
        tf.add("a", "b", None, shift(1.0, 0.0)).expect("edge");
        tf.add("b", "c", None, shift(1.0, 0.0)).expect("edge");
        assert!(
            tf.add("c", "a", None, shift(1.0, 0.0))
                .expect_err("refused")
                .contains("cycle")
        );
        assert!(
            tf.add("a", "a", None, shift(1.0, 0.0))
                .expect_err("refused")
                .contains("itself")
        );
        assert!(
            tf.add("x", "c", None, shift(1.0, 0.0))
                .expect_err("refused")
                .contains("two parents")
        );
        assert!(
            tf.add("b", "c", Some(5), shift(1.0, 0.0))
                .expect_err("refused")
                .contains("/tf_static")
        );
        tf.add("q", "r", None, shift(0.0, 0.0)).expect("edge");
        tf.finish();
        assert!(
            tf.lookup("a", "r", 0, 0)
                .expect_err("refused")
                .contains("not connected")
        );
    }
}
