//! Built-in procedural towns (stub).
use crate::world::RoadNetwork;
pub(crate) fn build(_name: &str) -> Option<RoadNetwork> {
    None
}
pub(crate) fn description(_name: &str) -> Option<&'static str> {
    None
}
