//! What a plot calls things: the devices a run's backends ran on (lavapipe named as the CPU
//! it is), the quantity a kind estimates (so a shadow plot never reads "AO time"), and series
//! of several devices that coincide (GPU parity), drawn once.

use crate::experiment::plot::{distinct, Series};
use crate::experiment::spec::Backend;
use crate::experiment::table::Row;

/// The name a plot gives a GPU adapter (`table.csv`'s `adapter`): Mesa's lavapipe, which
/// Vulkan reports as "llvmpipe", is "lavapipe (CPU)" (its times are a CPU's); another adapter
/// is "GPU" and its name.
pub fn gpu_label(adapter: &str) -> String {
    let lower = adapter.to_lowercase();
    if lower.contains("llvmpipe") || lower.contains("lavapipe") {
        return "lavapipe (CPU)".into();
    }
    match adapter.split('|').next().map(str::trim) {
        Some(name) if !name.is_empty() => format!("GPU {name}"),
        _ => "GPU".into(),
    }
}

/// The device names of a run's backends, read from its rows' adapters.
#[derive(Clone, Debug, PartialEq)]
pub struct Devices {
    gpu: String,
}

impl Devices {
    pub fn of(rows: &[Row]) -> Devices {
        let gpu = rows
            .iter()
            .find(|r| r.backend == Backend::Gpu)
            .map_or_else(|| "GPU".into(), |r| gpu_label(&r.adapter));
        Devices { gpu }
    }

    /// "CPU", or the GPU adapter's name ([`gpu_label`]).
    pub fn name(&self, b: Backend) -> &str {
        match b {
            Backend::Cpu => "CPU",
            Backend::Gpu => &self.gpu,
        }
    }
}

/// Two values that a plot draws as one: within this fraction of the larger.
pub const COINCIDE: f64 = 0.005;

/// A key's points on one device: `(key, device, points)`.
pub type DevicePart = (String, String, Vec<(f64, f64)>);

/// One series per `(key, device, points)`, except that the devices' series of one key whose
/// points are at the same x and agree in y within [`COINCIDE`] are one series, labelled
/// "KEY (CPU = lavapipe (CPU))"; the others are labelled "KEY, DEVICE" where the key has
/// several devices and "KEY" where it has one. Keys keep their first order; each series comes
/// with its key.
pub fn merge_devices(parts: &[DevicePart], line: bool) -> Vec<(String, Series)> {
    let series = |label: String, points: &Vec<(f64, f64)>| Series {
        label,
        points: points.clone(),
        line,
    };
    let mut out = Vec::new();
    for k in distinct(parts.iter().map(|(k, _, _)| k.as_str())) {
        let these: Vec<&DevicePart> = parts.iter().filter(|(key, _, _)| key == k).collect();
        if these.len() == 1 {
            out.push((k.to_string(), series(k.to_string(), &these[0].2)));
        } else if these[1..].iter().all(|p| coincide(&these[0].2, &p.2)) {
            let devices: Vec<&str> = these.iter().map(|p| p.1.as_str()).collect();
            let label = format!("{k} ({})", devices.join(" = "));
            out.push((k.to_string(), series(label, &these[0].2)));
        } else {
            out.extend(
                these
                    .iter()
                    .map(|(_, d, pts)| (k.to_string(), series(format!("{k}, {d}"), pts))),
            );
        }
    }
    out
}

/// Whether two point lists have the same x values and y values within [`COINCIDE`].
fn coincide(a: &[(f64, f64)], b: &[(f64, f64)]) -> bool {
    let sorted = |p: &[(f64, f64)]| {
        let mut p = p.to_vec();
        p.sort_by(|u, v| u.0.total_cmp(&v.0));
        p
    };
    let (a, b) = (sorted(a), sorted(b));
    a.len() == b.len()
        && a.iter()
            .zip(&b)
            .all(|(p, q)| p.0 == q.0 && (p.1 - q.1).abs() <= COINCIDE * p.1.abs().max(q.1.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lavapipe_is_named_as_the_cpu_it_runs_on() {
        let a = "llvmpipe (LLVM 15.0.6, 256 bits) | llvmpipe Mesa 22.3.6 (LLVM 15.0.6) | Vulkan";
        assert_eq!(gpu_label(a), "lavapipe (CPU)");
        assert_eq!(
            gpu_label("NVIDIA H200 | NVIDIA 550.54 | Vulkan"),
            "GPU NVIDIA H200"
        );
        assert_eq!(gpu_label(""), "GPU");
    }

    #[test]
    fn coinciding_devices_are_one_series_and_differing_ones_two() {
        let cpu = vec![(290.0, 2.053), (1090.0, 1.258)];
        // The GPU's 1.257 is 0.08% off: one series.
        let gpu = vec![(290.0, 2.053), (1090.0, 1.257)];
        // 2% off: two.
        let far = vec![(290.0, 2.053), (1090.0, 1.283)];
        let parts = vec![
            ("32²".to_string(), "CPU".to_string(), cpu.clone()),
            ("32²".to_string(), "lavapipe (CPU)".to_string(), gpu),
            ("64²".to_string(), "CPU".to_string(), cpu.clone()),
            ("64²".to_string(), "lavapipe (CPU)".to_string(), far),
            ("128²".to_string(), "CPU".to_string(), cpu.clone()),
        ];
        let s = merge_devices(&parts, true);
        let labels: Vec<&str> = s.iter().map(|(_, s)| s.label.as_str()).collect();
        assert_eq!(
            labels,
            [
                "32² (CPU = lavapipe (CPU))",
                "64², CPU",
                "64², lavapipe (CPU)",
                "128²"
            ]
        );
        let keys: Vec<&str> = s.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(keys, ["32²", "64²", "64²", "128²"]);
        // Points at other x never coincide.
        let shifted = vec![(291.0, 2.053), (1090.0, 1.258)];
        assert!(!coincide(&cpu, &shifted));
        assert!(coincide(&cpu, &cpu));
    }
}
