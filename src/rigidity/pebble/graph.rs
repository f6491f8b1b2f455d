//! The body-bar multigraph of a mechanism: bodies and joint nodes as vertices, B − k bars per
//! joint of grade k.

use super::PebbleOptions;
use crate::mechanism::Mechanism;

/// The body-bar multigraph: vertices `0..n_bodies` are bodies, the rest joint nodes.
pub(super) struct Graph {
    pub(super) weight: Vec<u8>,
    pub(super) n_bodies: usize,
    /// Bars as (vertex, vertex).
    pub(super) bars: Vec<(u32, u32)>,
    /// Joint index of each bar.
    pub(super) joint: Vec<u32>,
}

impl Graph {
    /// Build the multigraph, leaving out body `skip` (and every bar touching it).
    pub(super) fn build(m: &Mechanism, opts: &PebbleOptions, skip: Option<usize>) -> Graph {
        let b = m.b();
        let n_bodies = m.bodies.len();
        let mut g = Graph {
            weight: vec![b as u8; n_bodies],
            n_bodies,
            bars: Vec::new(),
            joint: Vec::new(),
        };
        for (ji, j) in m.joints.iter().enumerate() {
            // The reader validates indices; skipping bad ones keeps this panic-free anyway.
            let bodies: Vec<usize> = j
                .bodies
                .iter()
                .copied()
                .filter(|&x| x < n_bodies && Some(x) != skip)
                .collect();
            if bodies.len() < 2 {
                continue;
            }
            let c = b.saturating_sub(j.grade());
            let add = |g: &mut Graph, x: usize, y: usize, times: u32| {
                for _ in 0..times {
                    g.bars.push((x as u32, y as u32));
                    g.joint.push(ji as u32);
                }
            };
            if c > 0 {
                if bodies.len() == 2 {
                    add(&mut g, bodies[0], bodies[1], c);
                } else {
                    let node = g.weight.len();
                    g.weight.push(c as u8);
                    for &x in &bodies {
                        add(&mut g, x, node, c);
                    }
                }
            }
            if opts.with_inputs && j.driven > 0 {
                // Driven DOF lock pairs hub→other in order, at most the grade on each.
                let mut left = j.driven;
                for &x in &bodies[1..] {
                    let here = left.min(j.grade());
                    add(&mut g, bodies[0], x, here);
                    left -= here;
                }
            }
        }
        g
    }
}
