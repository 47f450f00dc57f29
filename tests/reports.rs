//! The pages and figures people look at: `report.html` of a run parses as HTML5 and links only files it wrote,
//! says pass or fail with the measured and required values, every figure's SVG (`--svg`) is well-formed with
//! its PNG's size, and the figures, SVGs and pages are the same bytes on any thread count. (The suite's page is checked by `tests/suite.rs`, the sweep's by `tests/cli_sweep.rs`,
//! a closed loop's by `tests/navigation.rs`, on the runs they already make.)
#![allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]

mod common;

use std::collections::BTreeMap;
use std::path::Path;

use common::{check_page, check_svg, oeg_with_threads, root, s, temp_dir};

fn run(out: &Path, extra: &[&str], threads: &str) -> std::process::Output {
    let scene = root().join("tests/scenes/decisions.toml");
    let mut args = vec!["run", s(&scene), "--out", s(out), "--set", "duration_s=5.0"];
    args.extend_from_slice(extra);
    oeg_with_threads(&args, Some(threads))
}

/// Every file of a run's folder that a person looks at (figures and pages), by relative path.
fn looked_at(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(base: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for entry in std::fs::read_dir(dir).expect("folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                walk(base, &path, out);
            } else if path
                .extension()
                .is_some_and(|e| e == "png" || e == "html" || e == "svg")
            {
                let name = path.strip_prefix(base).expect("inside").display().to_string();
                out.insert(name, std::fs::read(&path).expect("read"));
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

#[test]
fn a_run_page_parses_links_only_written_files_and_its_figures_and_svgs_are_the_same_bytes_on_1_and_2_threads()
{
    let dir = temp_dir("reports", "run");
    let (a, b) = (dir.join("two_threads"), dir.join("one_thread"));
    for (out, threads) in [(&a, "2"), (&b, "1")] {
        let o = run(out, &["--compare", "robust", "--svg"], threads);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let page = check_page(&a.join("report.html"));
    // The verdict first (each model's drive and cells, then its regression bounds), then both models side by
    // side, with every section.
    assert!(page.contains("id=\"verdict\""), "the verdict");
    assert!(
        page.contains("<b>paper</b>: <span class=\"badge"),
        "the paper model's line"
    );
    assert!(
        page.contains("<b>robust</b>: <span class=\"badge"),
        "the robust model's line"
    );
    assert!(page.contains("id=\"bounds\""), "the regression bounds");
    for section in [
        "id=\"decisions\"",
        "id=\"map\"",
        "id=\"observability\"",
        "id=\"metrics\"",
        "id=\"obstacles-paper\"",
        "id=\"obstacles-robust\"",
        "id=\"plan\"",
        "id=\"settings\"",
        "id=\"files\"",
        "src=\"decisions.png\"",
        "src=\"robust/decisions.png\"",
        "duration_s=5.0",
        "docs/metrics.md",
    ] {
        assert!(page.contains(section), "{section} missing from the page");
    }
    // Every file of the run is linked from its page.
    for file in [
        "metrics.json",
        "obstacles.csv",
        "plan.csv",
        "robust/metrics.json",
        "comparison.csv",
        "map.oeg",
    ] {
        assert!(page.contains(&format!("href=\"{file}\"")), "{file} is not linked");
    }
    let (one, two) = (looked_at(&b), looked_at(&a));
    assert!(two.len() >= 15, "{:?}", two.keys());
    // With --svg, every figure is also an SVG with its text as vectors.
    let pngs: Vec<&String> = two.keys().filter(|n| n.ends_with(".png")).collect();
    assert!(pngs.len() >= 10, "{pngs:?}");
    for png in pngs {
        let svg = a.join(png.replace(".png", ".svg"));
        assert!(check_svg(&svg) >= 3, "{}: too little text", svg.display());
    }
    assert_eq!(one.keys().collect::<Vec<_>>(), two.keys().collect::<Vec<_>>());
    for (name, bytes) in &two {
        assert!(one[name] == *bytes, "{name} differs between 1 and 2 threads");
    }
}

#[test]
fn each_models_failed_bounds_are_named_in_the_box_and_on_standard_output_apart_from_what_the_map_did() {
    let dir = temp_dir("reports", "fail");
    let out = dir.join("out");
    // The paper's model never answers "uncertain", robust does: the second model fails a bound the first
    // meets, and both fail the number of scans.
    let o = run(
        &out,
        &[
            "--compare",
            "robust",
            "--set",
            "expectations.num_scans={ max = 1 }",
            "--set",
            "expectations.uncertain_cells={ max = 0 }",
        ],
        "2",
    );
    // The exit status follows the run's own model.
    assert!(!o.status.success());
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = |model: &str| {
        stdout
            .lines()
            .find(|l| l.starts_with(&format!("{model} model: ")))
            .unwrap_or_else(|| panic!("no line for {model}: {stdout}"))
            .to_string()
    };
    for model in ["paper", "robust"] {
        // What the map made the robot do comes first, in its own words.
        let first = line(model);
        assert!(
            ["SAFE", "UNSAFE", "NO PATH"].iter().any(|w| first.contains(w)),
            "{first}"
        );
        assert!(stdout.contains("  cells: "), "{stdout}");
    }
    // Each model's bounds on a line of its own, in the models' order.
    let said: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("  regression bounds: "))
        .collect();
    assert_eq!(said.len(), 2, "{stdout}");
    assert!(
        said[0].contains("FAIL: num_scans = ") && !said[0].contains("uncertain_cells"),
        "the paper model's bounds: {stdout}"
    );
    assert!(
        said[1].contains("FAIL: num_scans = ") && said[1].contains("; uncertain_cells = "),
        "the robust model's bounds: {stdout}"
    );
    let page = check_page(&out.join("report.html"));
    assert!(page.contains("id=\"verdict\""));
    let bounds: Vec<&str> = page
        .lines()
        .filter(|l| l.contains("class=\"fail-text\""))
        .collect();
    assert_eq!(bounds.len(), 2, "one line of failed bounds per model: {bounds:?}");
    assert!(
        bounds[0].contains("<b>paper</b>") && bounds[0].contains("FAIL: num_scans = "),
        "{}",
        bounds[0]
    );
    assert!(
        bounds[1].contains("<b>robust</b>") && bounds[1].contains("uncertain_cells = "),
        "{}",
        bounds[1]
    );
    assert!(
        page.contains("they do not say the map is right"),
        "named as regression bounds"
    );
    let row = page
        .lines()
        .find(|l| l.contains("<td>num_scans</td>"))
        .expect("the failed expectation's row");
    assert!(row.contains("&lt;= 1") && row.contains("FAIL"), "{row}");
}

#[test]
fn the_embedded_font_ships_with_its_licence() {
    let fonts = root().join("eval/assets/fonts");
    assert!(fonts.join("DejaVuSans-subset.ttf").is_file());
    let licence = std::fs::read_to_string(fonts.join("LICENSE-DejaVu.txt")).expect("the font's licence");
    assert!(licence.contains("Bitstream Vera") && licence.contains("Permission is hereby granted"));
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README");
    assert!(readme.contains("DejaVu Sans") && readme.contains("LICENSE-DejaVu.txt"));
}
