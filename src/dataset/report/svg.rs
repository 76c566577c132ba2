//! Grouped bar charts as inline SVG for `pedsynth report`: no script, no fonts or styles from elsewhere, so the
//! page renders offline; every number is printed with a fixed precision, so the same data gives the same bytes.

use std::fmt::Write as _;

/// Series colours (Tableau 10): the dataset, then the one compared with it.
const COLOURS: [&str; 4] = ["#4e79a7", "#f28e2b", "#59a14f", "#e15759"];

const WIDTH: f64 = 720.0;
const HEIGHT: f64 = 330.0;
const LEFT: f64 = 72.0;
const RIGHT: f64 = 16.0;
const TOP: f64 = 48.0;
const BOTTOM: f64 = 112.0;

/// One named series: a value per category.
pub struct Series {
    pub name: String,
    pub values: Vec<f64>,
}

/// Escapes text for XML (and so for HTML).
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A round step for `ticks` intervals up to `max`.
fn tick_step(max: f64, ticks: usize) -> f64 {
    let raw = (max / ticks as f64).max(1e-12);
    let magnitude = 10f64.powf(raw.log10().floor());
    let norm = raw / magnitude;
    let nice = if norm <= 1.0 {
        1.0
    } else if norm <= 2.0 {
        2.0
    } else if norm <= 2.5 {
        2.5
    } else if norm <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * magnitude
}

/// A number for an axis label: no trailing zeros, at most 3 decimals.
fn label(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".to_owned() } else { s.to_owned() }
}

/// A grouped bar chart: one group per category, one bar per series, the y axis in `unit`. `title` becomes the
/// SVG's accessible title.
pub fn bars(title: &str, unit: &str, categories: &[String], series: &[Series]) -> String {
    let mut s = String::new();
    let plot_w = WIDTH - LEFT - RIGHT;
    let plot_h = HEIGHT - TOP - BOTTOM;
    let max = series
        .iter()
        .flat_map(|s| s.values.iter().copied())
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let step = tick_step(if max > 0.0 { max } else { 1.0 }, 4);
    let top = (max / step).ceil().max(1.0) * step;
    let y = |v: f64| TOP + plot_h * (1.0 - v / top);
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" role="img"><title>{}</title>"#,
        escape(title)
    );
    s.push_str(r##"<rect x="0" y="0" width="100%" height="100%" fill="#ffffff"/>"##);
    // Grid and y labels.
    let mut v = 0.0;
    while v <= top + step * 1e-9 {
        let _ = write!(
            s,
            r##"<line x1="{LEFT}" y1="{0:.1}" x2="{1:.1}" y2="{0:.1}" stroke="#dddddd"/><text x="{2:.1}" y="{3:.1}" font-size="11" text-anchor="end" fill="#333333">{4}</text>"##,
            y(v),
            LEFT + plot_w,
            LEFT - 6.0,
            y(v) + 4.0,
            label(v)
        );
        v += step;
    }
    let _ = write!(
        s,
        r##"<text x="14" y="{0:.1}" font-size="11" fill="#333333" transform="rotate(-90 14 {0:.1})" text-anchor="middle">{1}</text>"##,
        TOP + plot_h / 2.0,
        escape(unit)
    );
    // Bars.
    let n = categories.len().max(1) as f64;
    let group_w = plot_w / n;
    let bar_w = group_w * 0.8 / series.len().max(1) as f64;
    let rotate = categories.len() > 8 || categories.iter().any(|c| c.chars().count() > 10);
    for (i, category) in categories.iter().enumerate() {
        let x0 = LEFT + group_w * i as f64 + group_w * 0.1;
        for (k, ser) in series.iter().enumerate() {
            let value = ser.values.get(i).copied().unwrap_or(0.0);
            let value = if value.is_finite() { value.max(0.0) } else { 0.0 };
            let _ = write!(
                s,
                r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{}"><title>{}: {}</title></rect>"#,
                x0 + bar_w * k as f64,
                y(value),
                (bar_w - 1.0).max(0.5),
                TOP + plot_h - y(value),
                COLOURS[k % COLOURS.len()],
                escape(&format!("{} {category}", ser.name)),
                label(value)
            );
        }
        let cx = LEFT + group_w * (i as f64 + 0.5);
        let ly = TOP + plot_h + 14.0;
        if rotate {
            let _ = write!(
                s,
                r##"<text x="{cx:.1}" y="{ly:.1}" font-size="10" fill="#333333" text-anchor="end" transform="rotate(-35 {cx:.1} {ly:.1})">{}</text>"##,
                escape(category)
            );
        } else {
            let _ = write!(
                s,
                r##"<text x="{cx:.1}" y="{ly:.1}" font-size="11" fill="#333333" text-anchor="middle">{}</text>"##,
                escape(category)
            );
        }
    }
    let _ = write!(
        s,
        r##"<line x1="{LEFT}" y1="{0:.1}" x2="{1:.1}" y2="{0:.1}" stroke="#333333"/>"##,
        TOP + plot_h,
        LEFT + plot_w
    );
    // Legend.
    // Entries left to right, on a second row when the first is full (about 7 px per character at 12 px).
    let (mut lx, mut ly) = (LEFT + 8.0, 8.0);
    for (k, ser) in series.iter().enumerate() {
        let entry_w = 36.0 + 7.0 * ser.name.chars().count() as f64;
        if lx + entry_w > WIDTH - RIGHT && lx > LEFT + 8.0 {
            (lx, ly) = (LEFT + 8.0, ly + 18.0);
        }
        let _ = write!(
            s,
            r##"<rect x="{lx:.1}" y="{ly:.1}" width="12" height="12" fill="{}"/><text x="{:.1}" y="{:.1}" font-size="12" fill="#333333">{}</text>"##,
            COLOURS[k % COLOURS.len()],
            lx + 16.0,
            ly + 10.0,
            escape(&ser.name)
        );
        lx += entry_w;
    }
    s.push_str("</svg>");
    s
}

/// Histogram categories for bins of width `step` from `lo`: `"a–b"` labels, the last one open (`"≥ a"`).
pub fn bin_labels(lo: f64, step: f64, bins: usize) -> Vec<String> {
    (0..bins)
        .map(|i| {
            let a = lo + step * i as f64;
            if i + 1 == bins {
                format!("≥ {}", label(a))
            } else {
                format!("{}–{}", label(a), label(a + step))
            }
        })
        .collect()
}

/// Shares of `values` in bins of width `step` from `lo` (values past the last bin in it, below `lo` in the
/// first); all zero for no values.
pub fn histogram(values: &[f64], lo: f64, step: f64, bins: usize) -> Vec<f64> {
    let mut counts = vec![0.0; bins];
    for &v in values {
        if !v.is_finite() {
            continue;
        }
        let i = (((v - lo) / step).floor().max(0.0) as usize).min(bins - 1);
        counts[i] += 1.0;
    }
    let total: f64 = counts.iter().sum();
    if total > 0.0 {
        for c in &mut counts {
            *c /= total;
        }
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn histograms_are_shares_with_open_ends_and_charts_are_well_formed_xml() {
        let h = histogram(&[-1.0, 0.1, 0.5, 0.55, 9.0, f64::NAN], 0.0, 0.5, 3);
        assert_eq!(h, vec![0.4, 0.4, 0.2]);
        assert_eq!(bin_labels(0.0, 0.5, 3), ["0–0.5", "0.5–1", "≥ 1"]);
        let svg = bars(
            "a <title> & more",
            "share",
            &["x".to_owned(), "y\"".to_owned()],
            &[
                Series {
                    name: "one".to_owned(),
                    values: vec![0.25, 0.75],
                },
                Series {
                    name: "two".to_owned(),
                    values: vec![f64::NAN, 1.0],
                },
            ],
        );
        let doc = roxmltree::Document::parse(&svg).expect("well-formed");
        let rects = doc.descendants().filter(|n| n.has_tag_name("rect")).count();
        // Background, 4 bars, 2 legend swatches.
        assert_eq!(rects, 7);
        assert!(svg.contains("a &lt;title&gt; &amp; more"));
        assert_eq!(tick_step(0.75, 4), 0.2);
        assert_eq!(label(0.2 * 3.0), "0.6");
    }
}
