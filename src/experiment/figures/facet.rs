//! Splitting a figure's series into panels of at most [`MAX_SERIES`], the styles of the
//! comparison's families (the field, ray casting, each method: one colour and one marker
//! each, variants in shades and dashes) and the Pareto front of a set of points.

use crate::experiment::plot::{Marker, Panel, Style, Styled, MAX_SERIES};
use plotters::style::RGBColor;

/// Series that belong in one panel (a family, a positional count), under a title.
#[derive(Clone, Debug)]
pub struct Group {
    pub title: String,
    pub series: Vec<Styled>,
}

/// Panels of at most [`MAX_SERIES`]: each panel holds `context` (the same series in every
/// panel, as ray casting and the field's front are beside every method) and whole groups,
/// each placed in the first panel with room for it (first fit, in order); a group larger than
/// a panel's room is cut into parts "TITLE (1/2)", "(2/2)".
pub fn pack(groups: Vec<Group>, context: &[Styled], prefix: &str) -> Vec<Panel> {
    let room = MAX_SERIES.saturating_sub(context.len()).max(1);
    let mut parts: Vec<Group> = Vec::new();
    for g in groups.into_iter().filter(|g| !g.series.is_empty()) {
        if g.series.len() <= room {
            parts.push(g);
            continue;
        }
        let n = g.series.len().div_ceil(room);
        for (i, chunk) in g.series.chunks(room).enumerate() {
            parts.push(Group {
                title: format!("{} ({}/{n})", g.title, i + 1),
                series: chunk.to_vec(),
            });
        }
    }
    let mut bins: Vec<Vec<Group>> = Vec::new();
    for g in parts {
        let fits = |b: &Vec<Group>| {
            b.iter().map(|g| g.series.len()).sum::<usize>() + g.series.len() <= room
        };
        match bins.iter_mut().find(|b| fits(b)) {
            Some(b) => b.push(g),
            None => bins.push(vec![g]),
        }
    }
    bins.into_iter()
        .map(|b| {
            let titles: Vec<&str> = b.iter().map(|g| g.title.as_str()).collect();
            let mut series = context.to_vec();
            series.extend(b.iter().flat_map(|g| g.series.iter().cloned()));
            Panel::new(format!("{prefix}{}", titles.join(", ")), series)
        })
        .collect()
}

/// One panel titled `title` of `context` and every group where they fit in [`MAX_SERIES`],
/// else the groups [`pack`]ed beside `context`.
pub fn one_or_pack(
    groups: Vec<Group>,
    context: &[Styled],
    title: String,
    prefix: &str,
) -> Vec<Panel> {
    let total: usize = context.len() + groups.iter().map(|g| g.series.len()).sum::<usize>();
    if total > MAX_SERIES {
        return pack(groups, context, prefix);
    }
    let mut series = context.to_vec();
    series.extend(groups.into_iter().flat_map(|g| g.series));
    vec![Panel::new(title, series)]
}

/// The points no other point beats in both coordinates (smaller is better in each), sorted
/// by x: the lower-left staircase of a set of (cost, error) points.
pub fn front(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut out: Vec<(f64, f64)> = Vec::new();
    for q in p {
        if out.last().is_none_or(|l| q.1 < l.1) {
            out.push(q);
        }
    }
    out
}

/// The families of the comparison plots.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// The visibility field.
    Field,
    /// Our ray caster: the sweep over ray counts and the `raycast` method.
    RayCast,
    Embree,
    Sdf,
    AoField,
    /// A method the plots do not know (registered at run time): the `i`-th such.
    Other(usize),
}

impl Family {
    /// The family of a method named `name` (`others`: the unknown names met so far, which
    /// give each its own colour).
    pub fn of_method(name: &str, others: &mut Vec<String>) -> Family {
        match name {
            "raycast" => Family::RayCast,
            "embree" => Family::Embree,
            "sdf" => Family::Sdf,
            "aofield" => Family::AoField,
            _ => {
                let i = others.iter().position(|o| o == name).unwrap_or_else(|| {
                    others.push(name.to_string());
                    others.len() - 1
                });
                Family::Other(i)
            }
        }
    }

    /// Three shades, dark to light, and the marker.
    fn look(self) -> ([RGBColor; 3], Marker) {
        let (shades, marker) = match self {
            Family::Field => (
                [(8, 69, 148), (49, 130, 189), (107, 174, 214)],
                Marker::Circle,
            ),
            Family::RayCast => ([(0, 0, 0), (96, 96, 96), (160, 160, 160)], Marker::Square),
            Family::Embree => (
                [(140, 81, 10), (200, 120, 30), (230, 180, 100)],
                Marker::Diamond,
            ),
            Family::Sdf => ([(0, 109, 44), (49, 163, 84), (120, 198, 121)], Marker::Up),
            Family::AoField => (
                [(84, 39, 143), (128, 100, 190), (180, 160, 220)],
                Marker::Cross,
            ),
            Family::Other(i) => {
                let c = Style::palette(i + 5).color;
                ([(c.0, c.1, c.2); 3], Marker::Down)
            }
        };
        (shades.map(|(r, g, b)| RGBColor(r, g, b)), marker)
    }

    /// The style of a variant: `shade` (0 darkest; 3 and more cycle) and `variant` (0: filled
    /// and solid; 1: outlined and dashed; 2: filled and dashed; 3: outlined and solid).
    pub fn style(self, shade: usize, variant: usize) -> Style {
        let (shades, marker) = self.look();
        super::compare::variant_style(Style::new(shades[shade % 3], marker), variant)
    }
}

/// A colour of the viridis map at `t` in [0, 1] (dark purple to green; its last yellow
/// fifth, too light on white, left out): colours in order, as the values they stand for.
pub fn viridis(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (170.0, 220.0, 50.0),
    ];
    let t = t.clamp(0.0, 1.0) * 0.9 * (STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |u: f64, v: f64| (u + (v - u) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::plot::Series;

    fn s(label: &str) -> Styled {
        Series::scatter(label, vec![(1.0, 1.0)]).styled(Style::palette(0))
    }

    fn group(title: &str, n: usize) -> Group {
        Group {
            title: title.into(),
            series: (0..n).map(|i| s(&format!("{title}{i}"))).collect(),
        }
    }

    #[test]
    fn packing_keeps_every_panel_within_eight_and_every_series_once() {
        let context = [s("ray cast"), s("field front")];
        // Figure 6's methods: raycast 1, embree 1, sdf 6, aofield 3 (room 6 a panel).
        let groups = vec![
            group("raycast", 1),
            group("embree", 1),
            group("sdf", 6),
            group("aofield", 3),
        ];
        let panels = pack(groups, &context, "");
        let titles: Vec<&str> = panels.iter().map(|p| p.title.as_str()).collect();
        assert_eq!(titles, ["raycast, embree, aofield", "sdf"]);
        for p in &panels {
            assert!(p.series.len() <= MAX_SERIES);
            assert_eq!(p.series[0].series.label, "ray cast");
        }
        let total: usize = panels.iter().map(|p| p.series.len() - context.len()).sum();
        assert_eq!(total, 11);
        // A group larger than the room is cut.
        let panels = pack(vec![group("big", 13)], &context, "bunny: ");
        let titles: Vec<&str> = panels.iter().map(|p| p.title.as_str()).collect();
        assert_eq!(
            titles,
            ["bunny: big (1/3)", "bunny: big (2/3)", "bunny: big (3/3)"]
        );
        assert!(panels.iter().all(|p| p.series.len() <= MAX_SERIES));
    }

    #[test]
    fn the_front_is_the_lower_left_staircase() {
        let pts = [
            (1.0, 5.0),
            (2.0, 3.0),
            (2.5, 4.0),
            (3.0, 1.0),
            (0.5, 9.0),
            (3.0, 2.0),
        ];
        assert_eq!(
            front(&pts),
            [(0.5, 9.0), (1.0, 5.0), (2.0, 3.0), (3.0, 1.0)]
        );
        assert!(front(&[]).is_empty());
    }
}
