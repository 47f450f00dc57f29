//! Helpers shared by the tests that drive the built `oeg` binary.
#![allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `oeg` with `args`.
pub(crate) fn oeg(args: &[&str]) -> Output {
    oeg_with_threads(args, None)
}

/// Runs `oeg` with `args`, with `RAYON_NUM_THREADS` set when `threads` is given.
pub(crate) fn oeg_with_threads(args: &[&str], threads: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_oeg"));
    c.args(args);
    if let Some(t) = threads {
        c.env("RAYON_NUM_THREADS", t);
    }
    c.output().expect("the oeg binary runs")
}

/// `oeg map INPUT --resolution 0.05 --out OUT`, with `extra` arguments after them.
pub(crate) fn map_at(input: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["map", s(input), "--resolution", "0.05", "--out", s(out)];
    args.extend(extra);
    oeg(&args)
}

/// A fresh, empty temporary folder for one test (`group` keeps test files apart).
pub(crate) fn temp_dir(group: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("oeg-{group}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The repository root.
pub(crate) fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A path as a command-line argument.
pub(crate) fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// The standard output of a command that succeeded; a failure panics with both outputs.
pub(crate) fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "oeg failed: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The error of a command that failed with an error, not a panic (a panic exits with 101).
pub(crate) fn err(o: &Output) -> String {
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        !o.status.success(),
        "expected a failure: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert_ne!(o.status.code(), Some(101), "expected an error, not a panic: {e}");
    assert!(!e.contains("panicked"), "{e}");
    e
}

/// The error of `oeg sweep plan` on the sweep file `dir/NAME.toml`: `name = "NAME"`, `seed = 1`, the shipped
/// smoke base as its one scenario (lines 1 to 3), then `body` from line 4.
#[expect(clippy::disallowed_methods, reason = "a test writes its input directly")]
pub(crate) fn sweep_plan_error(dir: &Path, name: &str, body: &str) -> String {
    let base = root().join("sweeps/bases/smoke.toml");
    let path = dir.join(format!("{name}.toml"));
    let head = format!("name = \"{name}\"\nseed = 1\nscenarios = [{:?}]\n", s(&base));
    std::fs::write(&path, format!("{head}{body}")).expect("write");
    err(&oeg(&["sweep", "plan", s(&path)]))
}

/// Checks a written HTML page the way a browser reads it: it parses as HTML5 with no parse error, and every
/// link and image it references (`href`, `src`) that is not a web address or an anchor resolves to a file
/// written beside it. Returns the page's text.
pub(crate) fn check_page(page: &Path) -> String {
    use html5ever::tendril::TendrilSink;
    use markup5ever_rcdom::{Handle, NodeData, RcDom};
    let text = std::fs::read_to_string(page).unwrap_or_else(|e| panic!("{}: {e}", page.display()));
    let dom = html5ever::parse_document(RcDom::default(), Default::default())
        .from_utf8()
        .read_from(&mut text.as_bytes())
        .expect("reading from memory");
    let errors = dom.errors.borrow();
    assert!(
        errors.is_empty(),
        "{}: HTML5 parse errors: {errors:?}",
        page.display()
    );
    assert!(text.starts_with("<!DOCTYPE html>"), "{}", page.display());
    fn references(node: &Handle, out: &mut Vec<String>) {
        if let NodeData::Element { attrs, .. } = &node.data {
            for a in attrs.borrow().iter() {
                let name = &*a.name.local;
                if name == "href" || name == "src" {
                    out.push(a.value.to_string());
                }
            }
        }
        for child in node.children.borrow().iter() {
            references(child, out);
        }
    }
    let mut refs = Vec::new();
    references(&dom.document, &mut refs);
    let dir = page.parent().expect("a page's folder");
    let mut local = 0;
    for r in &refs {
        if r.starts_with("https://") || r.starts_with("http://") || r.starts_with('#') {
            continue;
        }
        assert!(
            !r.contains(".."),
            "{}: a link leaves the folder: {r}",
            page.display()
        );
        let decoded = percent_decode(r);
        assert!(
            dir.join(&decoded).exists(),
            "{}: {r} names no written file",
            page.display()
        );
        local += 1;
    }
    assert!(local > 0, "{}: no local links at all", page.display());
    text
}

/// Checks an SVG figure written beside its PNG: it parses as XML, its root is an `svg` element as wide and
/// tall as the PNG, every glyph it places is defined in it, and every embedded image is a PNG. Returns the
/// number of text lines it carries as vectors.
pub(crate) fn check_svg(svg: &Path) -> usize {
    let text = std::fs::read_to_string(svg).unwrap_or_else(|e| panic!("{}: {e}", svg.display()));
    let doc = roxmltree::Document::parse(&text).unwrap_or_else(|e| panic!("{}: not XML: {e}", svg.display()));
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "svg", "{}", svg.display());
    let png = std::fs::read(svg.with_extension("png")).expect("the PNG beside the SVG");
    let info = png::Decoder::new(std::io::Cursor::new(png))
        .read_info()
        .expect("a PNG")
        .info()
        .clone();
    assert_eq!(root.attribute("width"), Some(info.width.to_string().as_str()));
    assert_eq!(root.attribute("height"), Some(info.height.to_string().as_str()));
    let xlink = "http://www.w3.org/1999/xlink";
    let defined: std::collections::BTreeSet<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("path"))
        .filter_map(|n| n.attribute("id"))
        .collect();
    for node in doc.descendants() {
        if node.has_tag_name("use") {
            let target = node.attribute((xlink, "href")).expect("a use names its glyph");
            assert!(
                defined.contains(target.trim_start_matches('#')),
                "{}: {target} is not defined",
                svg.display()
            );
        }
        if node.has_tag_name("image") {
            let data = node.attribute((xlink, "href")).expect("an image's data");
            assert!(
                data.starts_with("data:image/png;base64,iVBORw0KGgo"),
                "{}: an image that is not a PNG",
                svg.display()
            );
        }
    }
    doc.descendants()
        .filter(|n| n.has_tag_name("g") && n.attribute("aria-label").is_some())
        .count()
}

/// `%XX` escapes of a link decoded.
fn percent_decode(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut k = 0;
    while k < bytes.len() {
        if bytes[k] == b'%'
            && k + 2 < bytes.len()
            && let Ok(v) = u8::from_str_radix(&text[k + 1..k + 3], 16)
        {
            out.push(v);
            k += 3;
        } else {
            out.push(bytes[k]);
            k += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}
