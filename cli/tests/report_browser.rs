//! `imu-fdi-sim report` on every shipped log, and each page opened in a
//! real headless browser (Debian's `chromium`): no JavaScript error, no
//! empty plot, and a screenshot for the README (`docs/img/report.png`).
//!
//! CI installs chromium (`.ci/run`); without it the browser half is
//! skipped with a loud message, the report half still runs.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)] // test code

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_imu-fdi-sim"))
}

/// The repository root: the logs are named relative to it, as a user in
/// the repository would (the page quotes the path in its notes).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn data(name: &str) -> PathBuf {
    Path::new("tests/data").join(name)
}

fn tmp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("imu-fdi-report-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `report --json` on `log`; returns the JSON and the page path.
fn report(log: &str, dir: &Path) -> (serde_json::Value, PathBuf) {
    let html = dir.join(format!("{log}.html"));
    let svgs = dir.join(format!("{log}-svg"));
    let o = bin()
        .current_dir(root())
        .arg("report")
        .arg(data(log))
        .arg("--out")
        .arg(&html)
        .arg("--svg-dir")
        .arg(&svgs)
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{log}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{log}: stdout is not one JSON object: {e}"));
    // Every plot has its standalone SVG, plus the timeline.
    let n_svg = std::fs::read_dir(&svgs).unwrap().count();
    assert_eq!(n_svg as u64, v["plots"].as_u64().unwrap() + 1, "{log}");
    (v, html)
}

fn verdicts<'a>(v: &'a serde_json::Value, monitor: &str) -> Vec<&'a serde_json::Value> {
    v["verdicts"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|x| x["monitor"] == monitor)
        .collect()
}

fn chromium() -> Option<&'static str> {
    ["chromium", "chromium-browser"].into_iter().find(|c| {
        Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

fn headless(browser: &str) -> Command {
    let mut c = Command::new(browser);
    c.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--hide-scrollbars",
        "--virtual-time-budget=10000",
    ]);
    c
}

/// The DOM after the page's script ran.
fn dump_dom(browser: &str, page: &Path) -> String {
    let o = headless(browser)
        .arg("--dump-dom")
        .arg(format!("file://{}", page.display()))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}: chromium failed", page.display());
    String::from_utf8_lossy(&o.stdout).to_string()
}

/// The value of every `name="…"` attribute in `dom`.
fn attrs<'a>(dom: &'a str, name: &str) -> Vec<&'a str> {
    let key = format!("{name}=\"");
    dom.match_indices(&key)
        .filter_map(|(i, _)| {
            let rest = &dom[i + key.len()..];
            rest.find('"').map(|e| &rest[..e])
        })
        .collect()
}

/// Checks a rendered page: script finished, no error, every plot drew
/// points. Returns the number of plots drawn.
fn check_dom(dom: &str, what: &str) -> usize {
    assert_eq!(
        attrs(dom, "data-render"),
        ["done"],
        "{what}: the script did not finish"
    );
    assert_eq!(
        attrs(dom, "data-js-errors"),
        ["0"],
        "{what}: JavaScript errors: {}",
        dom.split("id=\"js-errors\">")
            .nth(1)
            .unwrap_or("")
            .split("</pre>")
            .next()
            .unwrap_or("")
    );
    assert_eq!(attrs(dom, "data-empty-plots"), [""], "{what}: empty plots");
    let points = attrs(dom, "data-points");
    assert!(!points.is_empty(), "{what}: no plot drawn");
    for p in &points {
        let n: usize = p.parse().unwrap();
        assert!(n > 0, "{what}: a plot drew nothing");
    }
    points.len()
}

#[test]
fn every_shipped_log_gives_a_page_that_renders_without_errors() {
    let dir = tmp_dir();
    let logs = [
        "ap_log171_3imu.csv",
        "ap_log171_head.bin",
        "px4_fmuv3_outdoor_flight.ulg",
    ];
    let mut pages = Vec::new();
    for log in logs {
        let (v, html) = report(log, &dir);
        let n_imus = v["imus"].as_u64().unwrap() as usize;
        // One verdict per IMU channel and monitor.
        assert_eq!(verdicts(&v, "ukf").len(), 6 * n_imus, "{log}");
        assert_eq!(verdicts(&v, "parity").len(), 6 * n_imus, "{log}");
        let total = v["healthy"].as_u64().unwrap()
            + v["faulty"].as_u64().unwrap()
            + v["not_judged"].as_u64().unwrap();
        assert_eq!(total as usize, 12 * n_imus, "{log}");
        assert!(v["plots"].as_u64().unwrap() >= 2, "{log}: {v}");
        let size = v["html_bytes"].as_u64().unwrap();
        assert!(size < 20_000_000, "{log}: {size} bytes");
        pages.push((log, v, html));
    }
    // What each log can and cannot be judged on, and why.
    let csv = &pages[0].1;
    assert_eq!(csv["imus"], 3);
    for x in verdicts(csv, "ukf") {
        assert_eq!(x["state"], "not_judged");
        assert!(x["why"].as_str().unwrap().contains("no aiding"), "{x}");
    }
    assert!(verdicts(csv, "parity")
        .iter()
        .all(|x| x["state"] != "not_judged"));
    let bin = &pages[1].1;
    assert_eq!(bin["imus"], 3);
    assert_eq!(bin["not_judged"], 0, "{bin}");
    let ulg = &pages[2].1;
    assert_eq!(ulg["imus"], 1);
    for x in verdicts(ulg, "parity") {
        assert_eq!(x["state"], "not_judged");
        assert!(x["why"].as_str().unwrap().contains("three IMUs"), "{x}");
    }
    assert!(verdicts(ulg, "ukf").iter().any(|x| x["state"] == "healthy"));

    let Some(browser) = chromium() else {
        eprintln!(
            "\n!!!!!!!! SKIPPED the headless-browser half: no `chromium` on PATH \
             (apt-get install -y chromium; .ci/run installs it) !!!!!!!!\n"
        );
        return;
    };
    for (log, v, html) in &pages {
        let dom = dump_dom(browser, html);
        let drawn = check_dom(&dom, log);
        // Every plot and the timeline were drawn.
        assert_eq!(drawn as u64, v["plots"].as_u64().unwrap() + 1, "{log}");
    }
    // The check can fail: the same page with a script error is caught.
    let (_, _, html) = &pages[2];
    let broken = dir.join("broken.html");
    let text = std::fs::read_to_string(html).unwrap();
    std::fs::write(
        &broken,
        text.replace("redraw();\n  document", "redraw(); null.x;\n  document"),
    )
    .unwrap();
    let dom = dump_dom(browser, &broken);
    assert_eq!(attrs(&dom, "data-js-errors"), ["1"]);
    assert!(attrs(&dom, "data-render").is_empty());
    // The README's screenshot: the three-IMU DataFlash log.
    let shot = root().join("docs/img/report.png");
    let o = headless(browser)
        .arg("--window-size=1200,2300")
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("file://{}", pages[1].2.display()))
        .output()
        .unwrap();
    assert!(o.status.success());
    let png = std::fs::read(&shot).unwrap();
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 50_000,
        "{} bytes",
        png.len()
    );
}

#[test]
fn a_bad_log_is_one_line_on_stderr() {
    let dir = tmp_dir();
    let bad = dir.join("bad.bin");
    std::fs::write(&bad, b"not a log at all").unwrap();
    let o = bin()
        .arg("report")
        .arg(&bad)
        .arg("--out")
        .arg(dir.join("bad.html"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: ") && err.contains("bad.bin"),
        "{err}"
    );
    assert!(!dir.join("bad.html").exists());
}
