//! Static HTML pages for people to open and share: one self-contained file per run, suite or sweep, with its
//! figures as relative links to the images beside it. No script, no network access, no external style sheet;
//! the same inputs give the same bytes.
//!
//! Plain writers rather than a template crate: the pages are a handful of headings, tables and figures, and
//! every piece of text goes through [`escape`].

use super::{CsvRow, TableError, csv_table};

/// The page's style: readable on screen and in print, tables with aligned numbers, figures that shrink to fit.
const STYLE: &str = "\
body{font-family:'DejaVu Sans',Verdana,Arial,sans-serif;margin:1.5em auto;max-width:1500px;padding:0 1em;\
color:#111;line-height:1.4}\
h1{font-size:1.6em;margin-bottom:.2em}h2{font-size:1.25em;margin-top:1.6em;border-bottom:1px solid #ccc}\
table{border-collapse:collapse;margin:.5em 0;font-size:.9em;display:block;max-width:100%;overflow-x:auto}\
th,td{border:1px solid #ccc;padding:.2em .5em;text-align:left;vertical-align:top}\
td.num{text-align:right;font-variant-numeric:tabular-nums}th{background:#f2f2f2}\
.verdict{padding:.6em 1em;border:2px solid;margin:1em 0;font-size:1.1em}\
.pass{border-color:#1a7f37;background:#e9f7ee}.fail{border-color:#c62828;background:#fdecea}\
.neutral{border-color:#888;background:#f5f5f5}.verdict ul{margin:.3em 0;padding-left:1.2em}\
.badge{font-weight:bold;padding:0 .4em;border-radius:3px;color:#fff}.badge.safe{background:#1a7f37}\
.badge.unsafe{background:#c62828}.badge.nopath{background:#9a6700}\
.pass-text{color:#1a7f37}.fail-text{color:#c62828;font-weight:bold}\
.row{display:flex;flex-wrap:wrap;gap:1em;align-items:flex-start}\
figure{margin:0;flex:1 1 420px;min-width:0}figure img{max-width:100%;height:auto;border:1px solid #ddd}\
figcaption{font-size:.85em;color:#444}img.thumb{width:220px;height:auto;border:1px solid #ddd}\
code,pre{font-family:'DejaVu Sans Mono',monospace;font-size:.9em}pre{background:#f7f7f7;padding:.5em;\
overflow-x:auto}ul.files{columns:3 18em}.muted{color:#666}";

/// Text made safe for HTML element content and attribute values.
pub(crate) fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for ch in text.chars() {
        match ch {
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

/// A relative link's target: each path segment percent-encoded where it is not a plain file-name character,
/// `/`-separated whatever the platform.
pub(crate) fn href(relative: &std::path::Path) -> String {
    relative
        .components()
        .map(|c| {
            c.as_os_str()
                .to_string_lossy()
                .bytes()
                .map(|b| {
                    if b.is_ascii_alphanumeric() || b"-_.~".contains(&b) {
                        (b as char).to_string()
                    } else {
                        format!("%{b:02X}")
                    }
                })
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join("/")
}

/// A page being written: sections are appended in order, then [`Page::finish`] gives the document.
#[derive(Debug, Clone)]
pub(crate) struct Page {
    title: String,
    body: String,
}

impl Page {
    /// An empty page titled `title` (shown as its heading).
    pub(crate) fn new(title: &str) -> Self {
        Self {
            title: title.to_string(),
            body: String::new(),
        }
    }

    /// A section heading with an `id` to link to.
    pub(crate) fn heading(&mut self, id: &str, text: &str) {
        self.body
            .push_str(&format!("<h2 id=\"{}\">{}</h2>\n", escape(id), escape(text)));
    }

    /// A paragraph of plain text.
    pub(crate) fn paragraph(&mut self, text: &str) {
        self.body.push_str(&format!("<p>{}</p>\n", escape(text)));
    }

    /// Markup written as given: the caller escapes what it holds.
    pub(crate) fn raw(&mut self, html: &str) {
        self.body.push_str(html);
        self.body.push('\n');
    }

    /// A table of text cells; numbers are right-aligned.
    pub(crate) fn table<S: AsRef<str>>(&mut self, header: &[S], rows: &[Vec<String>]) {
        self.body.push_str(&table_html(header, rows));
    }

    /// Figures side by side (one per `(image, caption)`), each image a link to itself at full size.
    pub(crate) fn figures(&mut self, figures: &[(String, String)]) {
        self.body.push_str("<div class=\"row\">\n");
        for (src, caption) in figures {
            self.body.push_str(&format!(
                "<figure><a href=\"{src}\"><img src=\"{src}\" alt=\"{c}\"></a><figcaption>{c}</figcaption></figure>\n",
                src = escape(src),
                c = escape(caption)
            ));
        }
        self.body.push_str("</div>\n");
    }

    /// A list of links, each `(target, text)`.
    pub(crate) fn links(&mut self, links: &[(String, String)]) {
        self.body.push_str("<ul class=\"files\">\n");
        for (target, text) in links {
            self.body.push_str(&format!(
                "<li><a href=\"{}\">{}</a></li>\n",
                escape(target),
                escape(text)
            ));
        }
        self.body.push_str("</ul>\n");
    }

    /// The whole document.
    pub(crate) fn finish(self) -> String {
        format!(
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
             <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
             <meta name=\"generator\" content=\"oeg {version}\">\n<title>{title}</title>\n\
             <style>{STYLE}</style>\n</head>\n<body>\n<h1>{title}</h1>\n{body}\
             <p class=\"muted\">Written by oeg {version}.</p>\n</body>\n</html>\n",
            version = env!("CARGO_PKG_VERSION"),
            title = escape(&self.title),
            body = self.body,
        )
    }
}

/// Whether a table cell holds a number (right-aligned).
fn is_number(cell: &str) -> bool {
    !cell.is_empty() && cell.trim_start_matches('-').parse::<f64>().is_ok()
}

/// A table of text cells as HTML.
pub(crate) fn table_html<S: AsRef<str>>(header: &[S], rows: &[Vec<String>]) -> String {
    let mut out = String::from("<table>\n<thead><tr>");
    for h in header {
        out.push_str(&format!("<th>{}</th>", escape(h.as_ref())));
    }
    out.push_str("</tr></thead>\n<tbody>\n");
    for row in rows {
        out.push_str("<tr>");
        for cell in row {
            if is_number(cell) {
                out.push_str(&format!("<td class=\"num\">{}</td>", escape(cell)));
            } else {
                out.push_str(&format!("<td>{}</td>", escape(cell)));
            }
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</tbody>\n</table>\n");
    out
}

/// One CSV field as it reads in a page: whole numbers as they are, other numbers with 3 decimals (more for
/// small ones), an empty field as `-`.
pub(crate) fn field(text: &str) -> String {
    if text.is_empty() {
        return "-".into();
    }
    if text.bytes().all(|b| b.is_ascii_digit() || b == b'-') {
        return text.to_string();
    }
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v != 0.0 && v.abs() < 0.001 => format!("{v:.2e}"),
        Ok(v) if v.is_finite() => format!("{v:.3}"),
        _ => text.to_string(),
    }
}

/// The rows of a CSV table (header first, as [`super::csv_bytes`] writes it) as an HTML table, without the
/// columns named in `drop`: the same rows as the job's CSV file.
///
/// # Errors
/// [`TableError`] when the bytes are not CSV.
pub(crate) fn csv_to_html(csv: &[u8], drop: &[&str]) -> Result<String, TableError> {
    let mut reader = csv::ReaderBuilder::new().has_headers(true).from_reader(csv);
    let header = reader.headers()?.clone();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&k| !drop.contains(&&header[k]))
        .collect();
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record?;
        rows.push(
            keep.iter()
                .map(|&k| field(record.get(k).unwrap_or_default()))
                .collect(),
        );
    }
    let names: Vec<&str> = keep.iter().map(|&k| &header[k]).collect();
    Ok(table_html(&names, &rows))
}

/// [`csv_to_html`] of [`CsvRow`]s.
///
/// # Errors
/// As [`csv_to_html`], and a row that is not one flat record.
pub(crate) fn rows_to_html<'a, T: CsvRow + 'a>(
    rows: impl IntoIterator<Item = &'a T>,
    drop: &[&str],
) -> Result<String, TableError> {
    csv_to_html(&csv_table(rows)?, drop)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_everywhere() {
        assert_eq!(
            escape("a<b & \"c\" 'd'>"),
            "a&lt;b &amp; &quot;c&quot; &#39;d&#39;&gt;"
        );
        let mut page = Page::new("<script>");
        page.paragraph("x < y");
        page.table(&["<h>"], &[vec!["1 & 2".into(), "-0.5".into()]]);
        let html = page.finish();
        assert!(!html.contains("<script>") && html.contains("&lt;script&gt;"));
        assert!(html.contains("x &lt; y") && html.contains("<td class=\"num\">-0.5</td>"));
        assert!(html.starts_with("<!DOCTYPE html>"));
    }

    #[test]
    fn hrefs_are_relative_and_encoded() {
        assert_eq!(
            href(std::path::Path::new("robust/decisions map#1.png")),
            "robust/decisions%20map%231.png"
        );
    }

    #[test]
    fn fields_read_as_in_the_markdown_tables() {
        assert_eq!(field(""), "-");
        assert_eq!(field("12"), "12");
        assert_eq!(field("0.123456"), "0.123");
        assert_eq!(field("0.0000123"), "1.23e-5");
        assert_eq!(field("true"), "true");
    }
}
