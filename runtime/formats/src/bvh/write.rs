//! Writing BVH text: the hierarchy, then one row of channel values per frame.

use super::motion::Bvh;
use crate::error::{Error, Result};
use std::fmt::Write as _;
use std::path::Path;

impl Bvh {
    /// The BVH file text of this motion. Numbers use Rust's shortest round-trip form, so
    /// reading the text back gives the same values bit for bit.
    pub fn to_bvh_string(&self) -> String {
        let mut out = String::from("HIERARCHY\n");
        let children: Vec<Vec<usize>> = (0..self.joints().len())
            .map(|i| {
                (0..self.joints().len())
                    .filter(|&c| self.joints()[c].parent == Some(i))
                    .collect()
            })
            .collect();
        // Iterative depth-first writing: (joint, entering?).
        for root in (0..self.joints().len()).filter(|&j| self.joints()[j].parent.is_none()) {
            let mut stack = vec![(root, true, 0usize)];
            while let Some((j, enter, depth)) = stack.pop() {
                let pad = "\t".repeat(depth);
                let joint = &self.joints()[j];
                if enter {
                    let kind = if depth == 0 { "ROOT" } else { "JOINT" };
                    let o = joint.offset;
                    let _ = writeln!(out, "{pad}{kind} {}\n{pad}{{", joint.name);
                    let _ = writeln!(out, "{pad}\tOFFSET {} {} {}", o.x, o.y, o.z);
                    let _ = write!(out, "{pad}\tCHANNELS {}", joint.channels.len());
                    for c in &joint.channels {
                        let _ = write!(out, " {c}");
                    }
                    out.push('\n');
                    stack.push((j, false, depth));
                    for &c in children[j].iter().rev() {
                        stack.push((c, true, depth + 1));
                    }
                } else {
                    for e in &joint.end_sites {
                        let _ = writeln!(
                            out,
                            "{pad}\tEnd Site\n{pad}\t{{\n{pad}\t\tOFFSET {} {} {}\n{pad}\t}}",
                            e.x, e.y, e.z
                        );
                    }
                    let _ = writeln!(out, "{pad}}}");
                }
            }
        }
        let _ = writeln!(
            out,
            "MOTION\nFrames: {}\nFrame Time: {}",
            self.frame_count(),
            self.frame_time()
        );
        for k in 0..self.frame_count() {
            let mut first = true;
            for v in self.frame(k) {
                if !first {
                    out.push(' ');
                }
                first = false;
                let _ = write!(out, "{v}");
            }
            out.push('\n');
        }
        out
    }
}

/// Writes a BVH file.
pub fn write_bvh(path: impl AsRef<Path>, bvh: &Bvh) -> Result<()> {
    let path = path.as_ref();
    std::fs::write(path, bvh.to_bvh_string()).map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use crate::bvh::fixtures::{max_position_difference, shared_files};
    use crate::bvh::{parse_bvh, read_bvh, Channel, RotationOrder};

    #[test]
    fn export_in_every_order_and_back_keeps_every_global_position() {
        for path in shared_files() {
            let original = read_bvh(&path).unwrap();
            let text = original.to_bvh_string();
            assert_eq!(parse_bvh(&text, "again").unwrap(), original, "{path:?}");
            for order in RotationOrder::ALL {
                let there =
                    parse_bvh(&original.with_rotation_order(order).to_bvh_string(), "x").unwrap();
                assert!(max_position_difference(&original, &there) < 1e-6);
                let first = original.joints()[0]
                    .channels
                    .iter()
                    .filter_map(|c| match c {
                        Channel::Rotation(a) => Some(*a),
                        _ => None,
                    })
                    .collect::<Vec<_>>();
                let back_order = RotationOrder([first[0], first[1], first[2]]);
                let back =
                    parse_bvh(&there.with_rotation_order(back_order).to_bvh_string(), "y").unwrap();
                let d = max_position_difference(&original, &back);
                assert!(d < 1e-6, "{path:?} via {order}: {d}");
            }
        }
    }
}
