//! Library side of `pedsynth town list`, `pedsynth town show` and `pedsynth town export`: text and JSON
//! output, the PNG map and the OpenDRIVE file written atomically (temporary file, then rename). `main.rs` only parses arguments and calls these.

use std::path::Path;

use crate::world::{BUILTIN_TOWN_NAMES, RoadNetwork, WorldError, builtin};

/// The text `pedsynth town list` prints: one line per built-in town with its character and size.
pub fn town_list_text() -> String {
    let mut out = String::from("Built-in towns (procedural, modelled on the paper's CARLA towns; not CARLA's maps):\n");
    for name in BUILTIN_TOWN_NAMES {
        let desc = builtin::description(name).unwrap_or("");
        match RoadNetwork::builtin(name) {
            Some(net) => {
                let s = net.summary();
                out.push_str(&format!(
                    "  {name:<12} {desc} — {:.2} km driving lanes, {:.2} km sidewalk, {} junctions\n",
                    s.driving_lane_km, s.sidewalk_km, s.junction_count
                ));
            }
            None => out.push_str(&format!("  {name:<12} {desc}\n")),
        }
    }
    out.push_str(
        "Any OpenDRIVE file (.xodr 1.4-1.7) can be given by path instead, e.g. ../shared/maps/carla/Town01.xodr\n",
    );
    out
}

/// `pedsynth town show NAME_OR_XODR [--png out.png] [--json]`: loads the town, writes the PNG map if asked
/// and returns the text to print (the JSON summary if `json`, else a human-readable summary).
pub fn town_show(name_or_path: &str, png: Option<&Path>, json: bool) -> Result<String, WorldError> {
    let net = RoadNetwork::load(name_or_path)?;
    if let Some(path) = png {
        let bytes = net.render_png(2.0, 4096);
        write_atomically(path, &bytes)?;
    }
    let s = net.summary();
    if json {
        return Ok(serde_json::to_string_pretty(&s).expect("summary serialises") + "\n");
    }
    let mut out = format!(
        "{}: {} roads, {} lanes, {} junctions, {} crosswalks, {} obstacles\n  driving lanes {:.2} km, sidewalks {:.2} km\n  bounds x {:.1}..{:.1} m, y {:.1}..{:.1} m\n",
        s.name,
        s.road_count,
        s.lane_count,
        s.junction_count,
        s.crosswalk_count,
        s.obstacle_count,
        s.driving_lane_km,
        s.sidewalk_km,
        s.bounds_m[0],
        s.bounds_m[2],
        s.bounds_m[1],
        s.bounds_m[3]
    );
    if s.bike_lane_km > 0.0 {
        out.push_str(&format!("  bike lanes {:.2} km\n", s.bike_lane_km));
    }
    if s.signal_count > 0 {
        out.push_str(&format!(
            "  traffic lights: {} heads at {} junctions, {} controllers (phases)\n",
            s.signal_count, s.signalised_junction_count, s.signal_controller_count
        ));
        for (j, junction) in net.junctions.iter().enumerate() {
            let phases = crate::world::signals::junction_phases(&net.signals, j as u32);
            if phases == 0 {
                continue;
            }
            let heads: Vec<String> = (0..phases)
                .map(|k| {
                    let ids: Vec<&str> = net
                        .signals
                        .iter()
                        .filter(|g| g.junction == j as u32 && g.phase == k)
                        .map(|g| g.id.as_str())
                        .collect();
                    format!("phase {k}: {}", ids.join(" "))
                })
                .collect();
            out.push_str(&format!("    junction {}: {}\n", junction.id, heads.join("; ")));
        }
    }
    if let Some(path) = png {
        out.push_str(&format!("  map written to {}\n", path.display()));
    }
    Ok(out)
}

/// `pedsynth town export NAME --xodr OUT`: writes built-in town `name` as OpenDRIVE and returns the line to
/// print. An OpenDRIVE path or an unknown name is refused (unknown town).
pub fn town_export(name: &str, xodr: &Path) -> Result<String, WorldError> {
    let Some(text) = crate::world::opendrive::write::builtin_to_xodr(name)? else {
        return Err(WorldError::UnknownTown { name: name.into() });
    };
    write_atomically(xodr, text.as_bytes())?;
    let net = RoadNetwork::builtin(name).ok_or_else(|| WorldError::UnknownTown { name: name.into() })?;
    let s = net.summary();
    Ok(format!(
        "{name} written to {} as OpenDRIVE {}.{}: {} roads, {} junctions, {} crosswalks, {} buildings\n",
        xodr.display(),
        crate::world::opendrive::write::XODR_REV.0,
        crate::world::opendrive::write::XODR_REV.1,
        s.road_count,
        s.junction_count,
        s.crosswalk_count,
        s.obstacle_count
    ))
}

fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), WorldError> {
    crate::util::files::write_atomically(path, bytes).map_err(|source| WorldError::Io {
        path: path.display().to_string(),
        source,
    })
}
