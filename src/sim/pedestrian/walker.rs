//! The sidewalk walker of AI mode: greedy walking along the town's sidewalk graph, from node to node, never
//! over a crosswalk edge or onto a driving lane, preferring the edge that best continues the current heading.

use glam::DVec2;

use crate::world::{LaneType, RoadNetwork};

/// A walker's place on the sidewalk graph.
#[derive(Clone, Debug, Default)]
pub(crate) struct SidewalkWalker {
    /// Whether the walker still has somewhere to go (false when it found no node, or got stuck).
    pub active: bool,
    /// The node it came from, if any.
    prev: Option<u32>,
    /// The node it walks to.
    node: u32,
}

impl SidewalkWalker {
    /// A walker at `pos` heading along `heading`, bound for the nearest graph node (or the next one if that is
    /// behind it).
    pub(crate) fn start(net: &RoadNetwork, pos: DVec2, heading: DVec2) -> SidewalkWalker {
        let g = net.sidewalk_graph();
        let Some(n) = g.nearest_node(pos) else {
            return SidewalkWalker::default();
        };
        let mut w = SidewalkWalker {
            active: true,
            prev: None,
            node: n,
        };
        // If the nearest node is behind, head straight for the next one.
        if (g.nodes[n as usize] - pos).dot(heading) < 0.0 {
            w.advance(net, heading);
        }
        w
    }

    /// The node it walks to.
    pub(crate) fn target(&self, net: &RoadNetwork) -> DVec2 {
        net.sidewalk_graph().nodes[self.node as usize]
    }

    /// Moves on to the best next node; turns back at a dead end, and stops where there is nowhere to go.
    pub(crate) fn advance(&mut self, net: &RoadNetwork, heading: DVec2) {
        let g = net.sidewalk_graph();
        let here = g.nodes[self.node as usize];
        let mut best: Option<(f64, u32)> = None;
        for e in g.edges(self.node) {
            if e.crosswalk || Some(e.to) == self.prev || e.length_m < 1e-6 {
                continue;
            }
            let to = g.nodes[e.to as usize];
            let mid = (here + to) * 0.5;
            if net.lane_at(mid).is_some_and(|h| h.lane_type == LaneType::Driving) {
                continue;
            }
            let score = (to - here).normalize_or_zero().dot(heading);
            if best.is_none_or(|b| score > b.0) {
                best = Some((score, e.to));
            }
        }
        match (best, self.prev) {
            (Some((_, to)), _) => {
                self.prev = Some(self.node);
                self.node = to;
            }
            (None, Some(prev)) => self.turn_back_to(prev),
            (None, None) => self.active = false,
        }
    }

    /// Turns around: walks back to the node it came from.
    pub(crate) fn turn_around(&mut self) {
        if let Some(prev) = self.prev {
            self.turn_back_to(prev);
        }
    }

    fn turn_back_to(&mut self, prev: u32) {
        self.prev = Some(self.node);
        self.node = prev;
    }
}
