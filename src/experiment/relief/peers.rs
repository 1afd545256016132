//! The modern peers' rows of `experiment relief` (`crate::relief::peers`): the exact cell walk,
//! maximum mipmaps (Tevs, Ihrke, Seidel, I3D 2008), cone step mapping (Dummer 2006) and relaxed
//! cone stepping (Policarpo and Oliveira, GPU Gems 3 ch. 18, 2007) on the same maps, views,
//! exact reference and fetch accounting as the paper's search; with an adapter, each also on
//! its WGSL twin (`gpu::ReliefPeersKernel`), compared with the CPU frame.

use super::{measure, push, row, Measured, Pass, Setting};
use super::{ReliefRow, Result, ResultExt};
use crate::gpu::ReliefPeersKernel;
use crate::relief::peers::{render_peer, Peer, PeerData};
use crate::relief::view::render_gpu;

/// The peers and their settings, with their `method` names.
pub const PEERS: [(Peer, &str); 6] = [
    (Peer::CellWalk, "cell-walk"),
    (Peer::MaxMip, "max-mip"),
    (Peer::Cone { steps: 32 }, "cone-32"),
    (Peer::Cone { steps: 128 }, "cone-128"),
    (
        Peer::RelaxedCone {
            steps: 8,
            bisections: 6,
        },
        "relaxed-8+6",
    ),
    (
        Peer::RelaxedCone {
            steps: 16,
            bisections: 8,
        },
        "relaxed-16+8",
    ),
];

/// Renders `pass` with every peer (`repeats` timings, the fastest kept) and appends the rows;
/// with `gpu`, each also on the GPU twin, compared with the CPU frame.
pub(super) fn run_peers(
    pass: &Pass,
    data: &PeerData,
    gpu: Option<(&ReliefPeersKernel, &str)>,
    repeats: usize,
    rows: &mut Vec<ReliefRow>,
) -> Result<()> {
    for (peer, method) in PEERS {
        let cpu = || {
            render_peer(pass.map, data, &pass.view, &peer)
                .map_err(|e| super::Error::invalid("relief peer", e))
        };
        let gpu = gpu.map(|(kernel, adapter)| {
            let render = || render_gpu(kernel, pass.map, &pass.view, &peer);
            (adapter, move || {
                render().context(|| format!("relief peer {method}"))
            })
        });
        let m = Measured {
            setup_s: Some(data.build_time(&peer).as_secs_f64()),
            ..measure(pass, repeats, cpu, gpu)?
        };
        eprintln!(
            "relief: {} {} {}° {method}: {:.1} fetches per surface pixel, {:.4} s, missed {:.2}%{}",
            pass.table,
            pass.dataset.name(),
            pass.view.angle_deg,
            m.scores.surface.mean_fetches,
            m.time_s,
            100.0 * m.scores.missed_share,
            m.gpu
                .hit_mismatches_vs_cpu
                .map_or(String::new(), |d| format!("; GPU {d} pixel(s) differ")),
        );
        let (steps, bisections) = match peer {
            Peer::Cone { steps } => (steps, 0),
            Peer::RelaxedCone { steps, bisections } => (steps, bisections),
            Peer::CellWalk | Peer::MaxMip => (0, 0),
        };
        let at = Setting {
            method,
            // The cone methods' step count stands where the search's samples per unit stand.
            samples_per_unit: steps as f32,
            bisections,
            skips: 0,
            delta_rule: "",
        };
        push(rows, row(pass, &at, &m));
    }
    Ok(())
}
