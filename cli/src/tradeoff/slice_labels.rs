//! The labelled form of a PDF slice image: an SVG that embeds the PNG and names its
//! columns (target or learned, which hemisphere), its rows (the incident angle) and the
//! colour scale, so that the picture says what it shows wherever it is opened.

use std::fmt::Write as _;

/// Room for the row labels on the left and the column labels above, pixels.
const LEFT: usize = 92;
const TOP: usize = 44;
/// Room for the caption below.
const BOTTOM: usize = 50;
/// Smallest width, so that the caption fits beside a narrow (disk) image.
const MIN_WIDTH: usize = 540;

/// What the slice image holds, for its labels.
#[derive(Clone, Copy, Debug)]
pub struct Layout<'a> {
    /// Model name (the file stem).
    pub model: &'a str,
    /// Width and height of the PNG.
    pub size: (usize, usize),
    /// Side of one panel, pixels.
    pub panel: usize,
    /// Gap between panels, pixels.
    pub gap: usize,
    /// Incident polar angles of the rows, degrees.
    pub thetas: &'a [f64],
    /// Hemispheres of the column pairs (`true`: upper).
    pub sides: &'a [bool],
    /// Decades below each row's peak that the colour scale spans.
    pub decades: f64,
}

/// The SVG text: the PNG (`png`, its bytes) as a data URI, with labels.
pub fn svg(layout: &Layout<'_>, png: &[u8]) -> String {
    use base64::Engine as _;
    let (w, h) = layout.size;
    let (tw, th) = ((LEFT + w).max(MIN_WIDTH), TOP + h + BOTTOM);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{tw}" height="{th}" viewBox="0 0 {tw} {th}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{tw}" height="{th}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<image x="{LEFT}" y="{TOP}" width="{w}" height="{h}" href="data:image/png;base64,{}"/>"#,
        base64::engine::general_purpose::STANDARD.encode(png)
    );
    let step = layout.panel + layout.gap;
    for (pair, &upper) in layout.sides.iter().enumerate() {
        for (k, what) in ["target", "learned pdf()"].iter().enumerate() {
            let x = LEFT + (2 * pair + k) * step + layout.panel / 2;
            let _ = writeln!(
                s,
                r#"<text x="{x}" y="{}" text-anchor="middle" font-weight="bold">{what}</text>"#,
                TOP - 22
            );
            let side = if upper {
                "upper hemisphere"
            } else {
                "lower hemisphere"
            };
            let _ = writeln!(
                s,
                r#"<text x="{x}" y="{}" text-anchor="middle">{side}</text>"#,
                TOP - 7
            );
        }
    }
    for (row, theta) in layout.thetas.iter().enumerate() {
        let y = TOP + row * step + layout.panel / 2;
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{y}" text-anchor="end">θi = {theta}°</text>"#,
            LEFT - 8
        );
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="end">φi = 0 (+x)</text>"#,
            LEFT - 8,
            y + 15
        );
    }
    let caption = [
        format!(
            "{}: density per solid angle; each row on its own log scale, {} decades",
            escape(layout.model),
            layout.decades
        ),
        "below its peak (inferno). Orthographic view (wo.x, wo.y), +x to the right.".into(),
        "target: Y(f) |cos θo| normalised; learned: pdf(wi, wo) by the exact inverse.".into(),
    ];
    for (i, line) in caption.iter().enumerate() {
        let _ = writeln!(
            s,
            r#"<text x="4" y="{}" font-size="10">{line}</text>"#,
            TOP + h + 14 + 13 * i
        );
    }
    s.push_str("</svg>\n");
    s
}

/// `&`, `<` and `>` as XML entities.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_name_every_column_and_row() {
        let layout = Layout {
            model: "m<1>",
            size: (2 * 10 + 2, 3 * 10 + 4),
            panel: 10,
            gap: 2,
            thetas: &[0.0, 60.0, 89.0],
            sides: &[true],
            decades: 4.0,
        };
        let s = svg(&layout, &[1, 2, 3]);
        assert!(s.contains("base64,AQID"), "the PNG is embedded");
        assert_eq!(s.matches(">target<").count(), 1);
        assert_eq!(s.matches(">learned pdf()<").count(), 1);
        for t in ["θi = 0°", "θi = 60°", "θi = 89°"] {
            assert!(s.contains(t), "{t}");
        }
        assert!(s.contains("m&lt;1&gt;"));
        assert!(s.trim_end().ends_with("</svg>"));
    }
}
