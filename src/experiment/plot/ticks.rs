//! The ticks of an axis, chosen here rather than by plotters (whose logarithmic axes label
//! every mantissa of a short range, overprinting, and none of a range between two powers of
//! ten): labelled values spaced at least a label's extent apart on the drawn axis, at least two
//! of them inside the range wherever the range allows, and light grid lines between them.

/// The labelled values and the light grid lines of one axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Ticks {
    pub labels: Vec<f64>,
    pub light: Vec<f64>,
}

/// One axis as drawn: its data range, whether it is logarithmic, its length in pixels and the
/// least distance in pixels between two labels (a label's width on an x axis, its height on a
/// y axis, plus a gap).
#[derive(Clone, Copy, Debug)]
pub struct AxisLayout {
    pub lo: f64,
    pub hi: f64,
    pub log: bool,
    pub pixels: f64,
    pub min_gap: f64,
}

impl AxisLayout {
    /// The pixel position of `v` along the axis (0 at `lo`).
    pub fn position(&self, v: f64) -> f64 {
        let t = if self.log {
            (v.ln() - self.lo.ln()) / (self.hi.ln() - self.lo.ln())
        } else {
            (v - self.lo) / (self.hi - self.lo)
        };
        t * self.pixels
    }

    /// The least distance in pixels between consecutive values of `labels` (infinite for
    /// fewer than two).
    pub fn least_gap(&self, labels: &[f64]) -> f64 {
        labels
            .windows(2)
            .map(|w| (self.position(w[1]) - self.position(w[0])).abs())
            .fold(f64::INFINITY, f64::min)
    }
}

/// The ticks of `axis` (see the module's doc).
pub fn ticks(axis: &AxisLayout) -> Ticks {
    if axis.log {
        log_ticks(axis)
    } else {
        linear_ticks(axis)
    }
}

/// Multiples of a 1–2–5 step inside the range, the densest whose labels keep their distance.
fn linear_ticks(axis: &AxisLayout) -> Ticks {
    let (lo, hi) = (axis.lo, axis.hi);
    let span = hi - lo;
    if span.is_nan() || span <= 0.0 || !span.is_finite() {
        return Ticks {
            labels: vec![lo],
            light: vec![],
        };
    }
    // Steps from fine to coarse: the first whose labels are far enough apart.
    let base = 10f64.powf((span / 20.0).log10().floor());
    for k in 0..12 {
        let m = [1.0, 2.0, 2.5, 5.0][k % 4];
        let step = base * m * 10f64.powi((k / 4) as i32);
        let labels = multiples(lo, hi, step);
        if axis.least_gap(&labels) >= axis.min_gap {
            let fine = step / if m == 2.0 { 4.0 } else { 5.0 };
            let light = multiples(lo, hi, fine)
                .into_iter()
                .filter(|v| !labels.iter().any(|l| (l - v).abs() < 1e-9 * step))
                .collect();
            return Ticks { labels, light };
        }
    }
    Ticks {
        labels: vec![lo, hi],
        light: vec![],
    }
}

/// The multiples of `step` in [lo, hi] (0 exactly where it is one).
fn multiples(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last)
        .map(|i| if i == 0 { 0.0 } else { i as f64 * step })
        .collect()
}

/// Mantissa sets of a logarithmic axis, densest first, each with the decades it steps by.
const LOG_SETS: [(&[f64], i32); 8] = [
    (&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0], 1),
    (&[1.0, 2.0, 3.0, 5.0, 7.0], 1),
    (&[1.0, 2.0, 5.0], 1),
    (&[1.0, 3.0], 1),
    (&[1.0], 1),
    (&[1.0], 2),
    (&[1.0], 3),
    (&[1.0], 5),
];

/// Powers of ten and their 1–2–5 mantissas, the densest set whose labels keep their distance;
/// a range too short to hold two of them is labelled as a linear one would be (its values
/// placed logarithmically).
fn log_ticks(axis: &AxisLayout) -> Ticks {
    let (lo, hi) = (axis.lo, axis.hi);
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return linear_ticks(axis);
    }
    let decades = (hi / lo).log10();
    let in_range = |mantissas: &[f64], every: i32| -> Vec<f64> {
        let (e0, e1) = (lo.log10().floor() as i32 - 1, hi.log10().ceil() as i32 + 1);
        let mut out = Vec::new();
        for e in e0..=e1 {
            if e.rem_euclid(every) != 0 {
                continue;
            }
            for &m in mantissas {
                let v = m * 10f64.powi(e);
                if v >= lo * (1.0 - 1e-12) && v <= hi * (1.0 + 1e-12) {
                    out.push(v);
                }
            }
        }
        out
    };
    let light = if decades <= 6.0 {
        in_range(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0], 1)
    } else {
        in_range(&[1.0], 1)
    };
    for (mantissas, every) in LOG_SETS {
        let labels = in_range(mantissas, every);
        if labels.len() >= 2 && axis.least_gap(&labels) >= axis.min_gap {
            let light = light.into_iter().filter(|v| !labels.contains(v)).collect();
            return Ticks { labels, light };
        }
    }
    // Fewer than two of any set fit: linear steps, placed on the logarithmic axis, keeping
    // their distance at the crowded (upper) end.
    let mut t = linear_ticks(&AxisLayout {
        log: false,
        ..*axis
    });
    let mut k = 1;
    while t.labels.len() > 2 && axis.least_gap(&t.labels) < axis.min_gap && k < 8 {
        t = linear_ticks(&AxisLayout {
            log: false,
            min_gap: axis.min_gap * (1 << k) as f64,
            ..*axis
        });
        k += 1;
    }
    t.light = light
        .into_iter()
        .filter(|v| !t.labels.iter().any(|l| (l - v).abs() < 1e-9 * l.abs()))
        .collect();
    t
}

/// The text of the labels of one axis: plain numbers with at most three significant digits
/// where every label lies in [0.0001, 100000), else powers of ten as "10⁵" and "2×10⁵".
pub fn label_texts(labels: &[f64]) -> Vec<String> {
    let plain = labels
        .iter()
        .all(|&v| v == 0.0 || (1e-4..1e5).contains(&v.abs()));
    labels
        .iter()
        .map(|&v| if plain { tick(v) } else { power_of_ten(v) })
        .collect()
}

/// A compact plain label: 3 significant digits, no float noise.
pub fn tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-4..1e5).contains(&a) {
        return power_of_ten(v);
    }
    let digits = (2 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// `v` as "10ⁿ" or "m×10ⁿ" (m with up to 2 significant digits).
fn power_of_ten(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let mut e = v.abs().log10().floor() as i32;
    let mut m = v.abs() / 10f64.powi(e);
    if m >= 9.95 {
        m /= 10.0;
        e += 1;
    }
    let sign = if v < 0.0 { "-" } else { "" };
    let exp = superscript(e);
    if (m - 1.0).abs() < 0.005 {
        format!("{sign}10{exp}")
    } else {
        let m = format!("{m:.1}");
        let m = m.trim_end_matches('0').trim_end_matches('.');
        format!("{sign}{m}×10{exp}")
    }
}

fn superscript(e: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::new();
    if e < 0 {
        s.push('⁻');
    }
    for c in e.unsigned_abs().to_string().chars() {
        s.push(DIGITS[c.to_digit(10).unwrap_or(0) as usize]);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axis(lo: f64, hi: f64, log: bool) -> AxisLayout {
        AxisLayout {
            lo,
            hi,
            log,
            pixels: 700.0,
            min_gap: 60.0,
        }
    }

    /// Every labelled value is inside the range, the labels keep the least gap, and there
    /// are at least two.
    fn check(a: &AxisLayout) -> Ticks {
        let t = ticks(a);
        assert!(t.labels.len() >= 2, "{a:?}: {:?}", t.labels);
        let slack = 1e-9 * (a.hi - a.lo);
        for &v in &t.labels {
            assert!(v >= a.lo - slack && v <= a.hi + slack, "{a:?}: {v}");
        }
        assert!(a.least_gap(&t.labels) >= a.min_gap, "{a:?}: {:?}", t.labels);
        t
    }

    #[test]
    fn log_axes_are_labelled_across_their_range_without_overprinting() {
        // Six decades on 700 px: 117 px a decade, so every power of ten; 1–3 would put 1 and 3
        // 0.48 decades (56 px) apart, under the 60 px gap.
        let t = check(&axis(1e-3, 1e3, true));
        assert_eq!(t.labels, [1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0, 1000.0]);
        // Between two powers of ten (the ao2010_figure3 triangle axis, where plotters labels
        // nothing): the mantissas inside it.
        let t = check(&axis(25926.0, 58333.5, true));
        assert_eq!(t.labels, [3e4, 4e4, 5e4]);
        // 0.02 to 1.4 (the reflections Pareto): more than one label below 0.1.
        let t = check(&axis(0.02, 1.4, true));
        assert!(t.labels.iter().filter(|&&v| v < 0.1).count() >= 2, "{t:?}");
        // 290 to 16642 maps (figure 6): labels below 1000 as well.
        let t = check(&axis(193.0, 24963.0, true));
        assert!(t.labels.iter().any(|&v| v < 1000.0), "{t:?}");
        // A short range: the linear fallback, still two labels at least.
        check(&axis(5.1, 7.3, true));
        check(&axis(0.62, 0.71, true));
    }

    #[test]
    fn linear_axes_use_1_2_5_steps_and_keep_their_distance() {
        let t = check(&axis(-0.6, 1.1, false));
        assert!(t.labels.contains(&0.0));
        let steps: Vec<f64> = t.labels.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(steps.iter().all(|s| (s - steps[0]).abs() < 1e-9));
        check(&axis(0.0, 1.0, false));
        check(&axis(1.2e6, 1.3e6, false));
        // A crowded axis gets a coarser step.
        let narrow = AxisLayout {
            pixels: 100.0,
            ..axis(0.0, 100.0, false)
        };
        assert!(check(&narrow).labels.len() <= 2);
    }

    #[test]
    fn label_texts_are_compact_and_consistent_on_an_axis() {
        assert_eq!(tick(0.23000000000004), "0.23");
        assert_eq!(tick(12.5), "12.5");
        assert_eq!(tick(4000.0), "4000");
        assert_eq!(tick(0.0), "0");
        assert_eq!(label_texts(&[1e4, 1e5, 2e5]), ["10⁴", "10⁵", "2×10⁵"]);
        assert_eq!(label_texts(&[3e-4, 1e-3]), ["0.0003", "0.001"]);
        assert_eq!(label_texts(&[1e-5, 1e-3]), ["10⁻⁵", "10⁻³"]);
        assert_eq!(
            label_texts(&[0.01, 0.1, 1.0, 10.0]),
            ["0.01", "0.1", "1", "10"]
        );
    }
}
