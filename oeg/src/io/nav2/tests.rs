//! The nav2 map's tests.

use super::*;
use crate::geometry::{CellIndex, CellRegion};

/// 3 x 2 cells of 0.5 m from cell (-2, 4). Row y = 4 (bottom): free, blocked, unknown; row y = 5 (top):
/// traversable, uncertain, free.
fn decisions() -> Raster<Traversability> {
    use Traversability::*;
    Raster {
        window: crate::GridWindow::new(
            crate::GridGeometry::new(0.5).expect("resolution"),
            CellRegion::from_corners(CellIndex::new(-2, 4), CellIndex::new(0, 5)).expect("region"),
        ),
        values: vec![Free, Blocked, Unknown, Traversable, Uncertain, Free],
    }
}

#[test]
fn the_image_runs_from_the_max_y_row_and_the_origin_is_the_lower_left_corner() {
    let decisions = decisions();
    let (pgm, yaml) = nav2_map(&decisions, UncertainCells::Blocked, "map.pgm");
    let header = "P5\n# CREATOR: oeg 0.5\n3 2\n255\n";
    assert_eq!(&pgm[..header.len()], header.as_bytes());
    assert_eq!(&pgm[header.len()..], &[254, 0, 254, 254, 0, 205]);
    assert!(yaml.contains("origin: [-1, 2, 0.0]\n"), "{yaml}");
    assert!(yaml.contains("resolution: 0.5\n") && yaml.contains("mode: trinary\n"));
    // map_server's trinary reading: occupancy = (255 - grey) / 255.
    let occ = |g: u8| f64::from(255 - g) / 255.0;
    assert!(occ(PGM_FREE) < FREE_THRESH);
    assert!(occ(PGM_UNKNOWN) > FREE_THRESH && occ(PGM_UNKNOWN) < OCCUPIED_THRESH);
    assert!(occ(PGM_OCCUPIED) > OCCUPIED_THRESH);
    let (drivable, _) = nav2_map(&decisions, UncertainCells::Drivable, "map.pgm");
    assert_eq!(drivable[header.len() + 1], PGM_FREE);
}

#[test]
fn a_written_map_reads_back_with_its_decisions_and_origin() {
    use Traversability::*;
    let (pgm, yaml) = nav2_map(&decisions(), UncertainCells::Blocked, "map.pgm");
    let back = parse_nav2_map(&yaml, &pgm, 100).expect("reads");
    assert_eq!((back.rows, back.cols, back.resolution_m), (2, 3, 0.5));
    assert_eq!(back.origin_xy_m, [-1.0, 2.0]);
    // Drivable cells read free, uncertain ones blocked (as written), unknown stays unknown.
    assert_eq!(back.decisions, vec![Free, Blocked, Unknown, Free, Blocked, Free]);
    // map_saver's defaults, with comments and negate.
    let yaml = "# saved\nimage: \"m.pgm\"\nresolution: 0.05 # m\norigin: [0.0, 0.0, 0.0]\nnegate: 1\n";
    let negated = parse_nav2_map(yaml, b"P5 2 1 255 \x00\xff", 100).expect("negated");
    assert_eq!(negated.decisions, vec![Free, Blocked]);
}

#[test]
fn broken_maps_name_the_file_and_the_place() {
    let pgm = b"P5\n2 1\n255\n\x00\xfe";
    let yaml = "image: map.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n";
    assert!(parse_nav2_map(yaml, pgm, 100).is_ok());
    let cases: [(&str, &[u8], &str); 8] = [
        (
            "image: map.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n  - 4\n",
            pgm,
            "line 4: `- 4` is a list item that belongs to no key",
        ),
        (
            "image: map.pgm\norigin: [0, 0, 0]\n",
            pgm,
            "`resolution` is missing",
        ),
        (
            "image: map.pgm\nresolution: -1\norigin: [0, 0, 0]\n",
            pgm,
            "above 0",
        ),
        (
            "image: map.pgm\nresolution: 0.1\norigin: [0, 0, 0.5]\n",
            pgm,
            "yaw is 0.5",
        ),
        (
            "image: map.pgm\nresolution: 0.1\norigin: [0, 0, 0]\nmode: scale\n",
            pgm,
            "only `trinary`",
        ),
        (yaml, b"P5\n2 1\n255\n\x00", "1 bytes of pixels"),
        (yaml, b"P6\n2 1\n255\n\x00\x00", "`P5`"),
        (yaml, b"P5\n100000 100000\n255\n", "expected 1 to 100 pixels"),
    ];
    for (yaml, image, want) in cases {
        let e = parse_nav2_map(yaml, image, 100).expect_err(want).to_string();
        assert!(e.contains(want), "{e} lacks {want}");
        assert!(e.starts_with("map.yaml") || e.starts_with("map.pgm"), "{e}");
    }
}

#[test]
fn the_yaml_map_server_accepts_is_read() {
    let pgm = b"P5\n2 1\n255\n\x00\xfe";
    for yaml in [
        // Block-style origin, quoted values, a document marker, keys map_server ignores, comments.
        "---\nimage: 'map.pgm'\nmode: \"trinary\"\nresolution: \"0.1\"\norigin:\n  - 0.0\n  - '0'\n  - 0 # yaw\nnegate: '0'\noccupied_thresh: 0.65\nfree_thresh: 0.196\nsaved_by: map_saver\n...\n",
        "image: map.pgm\nresolution: 0.1\norigin:\n- 0\n- 0\n- 0\n",
        "\"image\": \"map#1.pgm\"\nresolution: 0.1 # metres\norigin: [ 0 , 0 , 0 ]\n",
    ] {
        let m = parse_nav2_map(yaml, pgm, 100).unwrap_or_else(|e| panic!("{yaml}: {e}"));
        assert_eq!((m.resolution_m, m.origin_xy_m), (0.1, [0.0, 0.0]), "{yaml}");
    }
    let e = parse_nav2_map(
        "image: map.pgm\nresolution: 0.1\norigin:\n  - 0\n  - 0\n",
        pgm,
        100,
    )
    .expect_err("two numbers")
    .to_string();
    assert!(
        e.contains("line 3: `origin: [0, 0]`, expected [x, y, yaw]"),
        "{e}"
    );
}
