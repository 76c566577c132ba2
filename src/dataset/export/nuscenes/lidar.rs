//! The LiDAR side of the nuScenes export: the dataset's points of some frames (Parquet or the seed's `.bin`
//! files) and each point's ring, for nuScenes' `.pcd.bin` (x, y, z, intensity, ring).

use std::collections::{BTreeMap, BTreeSet};

use crate::dataset::export::dataset::Dataset;
use crate::dataset::read::tables as read_tables;
use crate::error::Error;

/// The ring (channel, 0 = the top one) of a return at `(x, y, z)` in the sensor frame: its elevation seen from
/// the sensor, on the channels' even spacing from `upper_fov_deg` to `lower_fov_deg`.
pub(super) fn ring(l: &crate::spec::types::Lidar, x: f32, y: f32, z: f32) -> f32 {
    if l.channels <= 1 {
        return 0.0;
    }
    let elevation_deg = f64::from(z).atan2(f64::from(x).hypot(f64::from(y))).to_degrees();
    let spacing = (l.upper_fov_deg - l.lower_fov_deg) / f64::from(l.channels - 1);
    let ring = ((l.upper_fov_deg - elevation_deg) / spacing).round();
    ring.clamp(0.0, f64::from(l.channels - 1)) as f32
}

/// The LiDAR points of `frames` of a clip, by frame: `[x, y, z, intensity]` in CARLA's sensor frame (x forward,
/// y right, z up), in the order the dataset holds them. Reads the Parquet points or the seed's `.bin` files.
pub(crate) fn read_points(
    ds: &Dataset,
    clip: &str,
    frames: &BTreeSet<u32>,
) -> Result<BTreeMap<u32, Vec<[f32; 4]>>, Error> {
    let mut points: BTreeMap<u32, Vec<[f32; 4]>> = BTreeMap::new();
    let parquet = ds.layout.sensor_clip("lidar", clip, "parquet");
    if parquet.is_file() {
        for b in read_tables::read(&parquet, &["frame", "x", "y", "z", "intensity"])? {
            let f = b.u32s("frame")?;
            let (x, y, z, i) = (b.f32s("x")?, b.f32s("y")?, b.f32s("z")?, b.f32s("intensity")?);
            for r in (0..b.rows()).filter(|&r| frames.contains(&f.value(r))) {
                points
                    .entry(f.value(r))
                    .or_default()
                    .push([x.value(r), y.value(r), z.value(r), i.value(r)]);
            }
        }
        return Ok(points);
    }
    for &f in frames {
        if let Some(bin) = crate::dataset::read::lidar_view::read_bin(&ds.layout.sensor_frame("lidar", clip, f, "bin"))?
        {
            points.entry(f).or_default().extend(bin);
        }
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rings_follow_the_channels_elevations_from_the_top() {
        let l = crate::spec::types::Lidar {
            channels: 64,
            upper_fov_deg: 15.0,
            lower_fov_deg: -25.0,
            ..Default::default()
        };
        for i in [0u32, 1, 31, 63] {
            let el = crate::sensors::lidar::channel_elevation_deg(&l, i).to_radians();
            let (x, z) = (20.0 * el.cos(), 20.0 * el.sin());
            assert_eq!(ring(&l, x as f32, 0.0, z as f32), i as f32, "channel {i}");
        }
    }
}
