//! The profile chart: CPU and GPU milliseconds against instances, as plain SVG.

use super::profile_report::Row;
use crate::renderer::{CullMode, StereoMode};

/// What a chart panel plots of a row.
type Metric = fn(&Row) -> Option<f64>;

const PALETTE: [&str; 10] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf",
];

/// Two log-log panels (CPU ms and GPU ms against instances), one line per mode and cull.
/// Plain SVG: producing it needs no font; any viewer draws its text.
pub fn chart_svg(rows: &[Row]) -> String {
    let mut rigs: Vec<&str> = Vec::new();
    let mut kinds: Vec<(StereoMode, CullMode)> = Vec::new();
    let mut series: Vec<Series> = Vec::new();
    for r in rows {
        let rig = rigs.iter().position(|x| *x == r.rig).unwrap_or_else(|| {
            rigs.push(&r.rig);
            rigs.len() - 1
        });
        let kind = kinds
            .iter()
            .position(|k| *k == (r.mode, r.cull))
            .unwrap_or_else(|| {
                kinds.push((r.mode, r.cull));
                kinds.len() - 1
            });
        match series.iter_mut().find(|s| s.rig == rig && s.kind == kind) {
            Some(s) => s.rows.push(r),
            None => series.push(Series {
                name: format!("{}: {} / {:?} cull", r.rig, r.mode.name(), r.cull).to_lowercase(),
                rig,
                kind,
                rows: vec![r],
            }),
        }
    }
    for s in &mut series {
        s.rows.sort_by_key(|r| r.instances);
    }
    let (w, h): (f64, f64) = (460.0, 320.0);
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
        2.0 * w + 260.0,
        (h + 20.0).max(60.0 + 16.0 * series.len() as f64)
    );
    let panels: [(&str, Metric); 2] = [
        ("CPU ms per frame (prepare + encode + submit)", |r| {
            Some(r.cpu_ms_median)
        }),
        ("GPU ms per frame (timestamps)", |r| r.gpu_ms_median),
    ];
    for (p, (title, value)) in panels.iter().enumerate() {
        let x0 = p as f64 * w;
        svg += &panel(x0, w, h, title, &series, *value);
    }
    for (i, s) in series.iter().enumerate() {
        let y = 40.0 + 16.0 * i as f64;
        svg += &format!(
            "<line x1=\"{0}\" y1=\"{y}\" x2=\"{1}\" y2=\"{y}\" {2}/><text x=\"{3}\" y=\"{4}\">{5}</text>\n",
            2.0 * w + 10.0,
            2.0 * w + 30.0,
            s.stroke(),
            2.0 * w + 35.0,
            y + 4.0,
            s.name
        );
    }
    svg + "</svg>\n"
}

struct Series<'a> {
    name: String,
    rig: usize,
    kind: usize,
    rows: Vec<&'a Row>,
}

impl Series<'_> {
    /// Color by mode and cull, dash pattern by rig.
    fn stroke(&self) -> String {
        let dash = ["", "6,3", "2,2", "8,3,2,3"][self.rig % 4];
        format!(
            "stroke=\"{}\" stroke-width=\"2\" stroke-dasharray=\"{dash}\" fill=\"none\"",
            PALETTE[self.kind % PALETTE.len()]
        )
    }
}

fn panel(x0: f64, w: f64, h: f64, title: &str, series: &[Series], value: Metric) -> String {
    let points: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| {
            s.rows
                .iter()
                .filter_map(|r| value(r).map(|v| (r.instances as f64, v)))
        })
        .filter(|&(x, y)| x > 0.0 && y > 0.0)
        .collect();
    let mut out = format!(
        "<text x=\"{}\" y=\"16\" font-size=\"13\">{title}</text>\n",
        x0 + 50.0
    );
    if points.is_empty() {
        return out
            + &format!(
                "<text x=\"{}\" y=\"{}\">not measured on this adapter</text>\n",
                x0 + 60.0,
                h / 2.0
            );
    }
    let decades = |f: fn(f64, f64) -> f64, init: f64, axis: fn(&(f64, f64)) -> f64| {
        points.iter().map(axis).fold(init, f).log10()
    };
    let (lx0, lx1) = (
        decades(f64::min, f64::MAX, |p| p.0).floor(),
        decades(f64::max, 0.0, |p| p.0).ceil().max(1.0),
    );
    let (ly0, ly1) = (
        decades(f64::min, f64::MAX, |p| p.1).floor(),
        decades(f64::max, 0.0, |p| p.1).ceil(),
    );
    let (ly0, ly1) = (ly0, if ly1 <= ly0 { ly0 + 1.0 } else { ly1 });
    let (left, right, top, bottom) = (x0 + 60.0, x0 + w - 20.0, 30.0, h - 30.0);
    let px = |x: f64| left + (x.log10() - lx0) / (lx1 - lx0).max(1.0) * (right - left);
    let py = |y: f64| bottom - (y.log10() - ly0) / (ly1 - ly0) * (bottom - top);
    out += &format!(
        "<rect x=\"{left}\" y=\"{top}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#444\"/>\n",
        right - left,
        bottom - top
    );
    for d in lx0 as i32..=lx1 as i32 {
        let x = px(10f64.powi(d));
        out += &format!(
            "<line x1=\"{x}\" y1=\"{top}\" x2=\"{x}\" y2=\"{bottom}\" stroke=\"#ddd\"/><text x=\"{x}\" y=\"{}\" text-anchor=\"middle\">1e{d}</text>\n",
            bottom + 14.0
        );
    }
    for d in ly0 as i32..=ly1 as i32 {
        let y = py(10f64.powi(d));
        out += &format!(
            "<line x1=\"{left}\" y1=\"{y}\" x2=\"{right}\" y2=\"{y}\" stroke=\"#ddd\"/><text x=\"{}\" y=\"{}\" text-anchor=\"end\">1e{d}</text>\n",
            left - 4.0,
            y + 4.0
        );
    }
    out += &format!(
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">instances</text>\n",
        (left + right) / 2.0,
        h - 2.0
    );
    for s in series {
        let pts: Vec<String> = s
            .rows
            .iter()
            .filter_map(|r| {
                value(r)
                    .filter(|v| *v > 0.0)
                    .map(|v| format!("{:.1},{:.1}", px(r.instances as f64), py(v)))
            })
            .collect();
        out += &format!("<polyline points=\"{}\" {}/>\n", pts.join(" "), s.stroke());
    }
    out
}
