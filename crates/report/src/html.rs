//! The page's HTML: escaping, number formatting, tables and the page frame with its
//! style sheet. Pure string building; the same input gives the same bytes.

pub use rvtol_engine::format::escape_markup as escape;

/// A figure as the text report writes it ([`rvtol_engine::format::format_sig`]: 5
/// significant digits), "n/a" when absent or not finite.
pub fn number(value: Option<f64>) -> String {
    match value {
        Some(v) if v.is_finite() => rvtol_engine::format::format_sig(v),
        _ => "n/a".into(),
    }
}

/// An interval "a .. b"; an open end reads "below min" or "above max".
pub fn interval(low: Option<f64>, high: Option<f64>) -> String {
    let low = low.map_or("below min".to_string(), |v| number(Some(v)));
    let high = high.map_or("above max".to_string(), |v| number(Some(v)));
    format!("{low} .. {high}")
}

/// A table: a header row and body rows of already escaped cells; `numeric` columns are
/// right-aligned.
pub fn table(header: &[&str], rows: &[Vec<String>], numeric: &[usize]) -> String {
    let mut out = String::from("<table>\n<thead><tr>");
    for (i, h) in header.iter().enumerate() {
        let class = if numeric.contains(&i) {
            " class=\"num\""
        } else {
            ""
        };
        out.push_str(&format!("<th{class}>{}</th>", escape(h)));
    }
    out.push_str("</tr></thead>\n<tbody>\n");
    for row in rows {
        out.push_str("<tr>");
        for (i, cell) in row.iter().enumerate() {
            let class = if numeric.contains(&i) {
                " class=\"num\""
            } else {
                ""
            };
            out.push_str(&format!("<td{class}>{cell}</td>"));
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</tbody>\n</table>\n");
    out
}

/// A figure: an inline SVG with a caption.
pub fn figure(svg: &str, caption: &str) -> String {
    // The XML prologue plotters may write is not allowed inside HTML.
    let svg = svg.trim_start_matches(|c| c != '<');
    let svg = if svg.starts_with("<?xml") {
        svg.split_once("?>")
            .map_or(svg, |(_, rest)| rest.trim_start())
    } else {
        svg
    };
    // Scale with the column: the drawing keeps its aspect ratio through its viewBox.
    let svg = svg.replacen("<svg ", "<svg class=\"chart\" role=\"img\" ", 1);
    format!(
        "<figure>\n{svg}\n<figcaption>{}</figcaption>\n</figure>\n",
        escape(caption)
    )
}

const STYLE: &str = r#"
:root { color-scheme: light; }
body { font-family: -apple-system, "Segoe UI", "DejaVu Sans", Helvetica, Arial, sans-serif;
  color: #1d1d1f; background: #fff; margin: 0 auto; max-width: 1180px; padding: 24px 32px 64px;
  line-height: 1.45; font-size: 15px; }
h1 { font-size: 26px; margin: 0 0 4px; }
h2 { font-size: 21px; margin: 40px 0 8px; padding-bottom: 4px; border-bottom: 2px solid #1f4e79; }
h3 { font-size: 17px; margin: 28px 0 6px; }
p.lead { color: #444; margin: 4px 0 16px; max-width: 980px; }
p.note { color: #555; font-size: 13.5px; max-width: 980px; }
table { border-collapse: collapse; margin: 8px 0 16px; font-size: 13.5px; }
th, td { border-bottom: 1px solid #ddd; padding: 3px 10px; text-align: left; vertical-align: top; }
th { background: #f3f5f8; font-weight: 600; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
th.num { text-align: right; }
td small { color: #555; }
table.meta td:first-child { color: #555; white-space: nowrap; }
.pair { display: grid; grid-template-columns: repeat(auto-fit, minmax(min(520px, 100%), 1fr)); gap: 12px; }
figure { margin: 6px 0; }
figcaption { font-size: 12.5px; color: #555; margin-top: 2px; }
svg.chart { width: 100%; height: auto; border: 1px solid #eee; }
.status-met { color: #2e7d32; font-weight: 600; }
.status-bad { color: #c62828; font-weight: 600; }
nav { font-size: 14px; margin: 8px 0 0; }
nav a { margin-right: 14px; color: #1f4e79; }
footer { margin-top: 48px; font-size: 12.5px; color: #777; }
@page { size: A4; margin: 12mm 10mm; }
@media print {
  body { max-width: none; padding: 0; font-size: 10.5px; }
  h1 { font-size: 19px; } h2 { font-size: 15px; margin-top: 20px; } h3 { font-size: 12.5px; }
  p.note, figcaption { font-size: 9.5px; }
  table { font-size: 9px; }
  th, td { padding: 1px 4px; }
  .pair { grid-template-columns: minmax(0, 1fr) minmax(0, 1fr); }
  nav { display: none; }
  h2, h3 { break-after: avoid; }
  figure, tr { break-inside: avoid; }
}
"#;

/// The page around its body.
pub fn page(title: &str, body: &str) -> String {
    let mut out =
        String::from("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    out.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    out.push_str(&format!(
        "<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n",
        escape(title)
    ));
    out.push_str(body);
    out.push_str("</body>\n</html>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_like_the_text_report() {
        assert_eq!(number(Some(1.664433435)), "1.6644");
        assert_eq!(number(Some(774010.0)), "774010");
        assert_eq!(number(Some(0.000123456)), "0.00012346");
        assert_eq!(number(Some(f64::NAN)), "n/a");
        assert_eq!(number(None), "n/a");
        assert_eq!(interval(None, Some(2.0)), "below min .. 2.0000");
    }

    #[test]
    fn text_is_escaped() {
        assert_eq!(escape("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
    }
}
