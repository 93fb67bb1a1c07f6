//! The built-in scenarios ship as TOML files in `scenarios/`; this test
//! keeps each file identical to its built-in (regenerate with
//! `UPDATE_SCENARIO_FILES=1 cargo test -p imu-fdi-cli --test scenario_files`).

use std::path::PathBuf;

use hal_sim::Scenario;
use imu_fdi_cli::io::scenario_file::{parse_scenario, read_scenario, scenario_toml};

fn path(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios")).join(format!("{name}.toml"))
}

#[test]
fn every_builtin_ships_as_an_identical_toml_file() {
    for name in Scenario::BUILTIN {
        let scn = Scenario::builtin(name).unwrap();
        if std::env::var_os("UPDATE_SCENARIO_FILES").is_some() {
            std::fs::write(path(name), scenario_toml(&scn).unwrap()).unwrap();
        }
        let file = read_scenario(&path(name)).unwrap();
        assert_eq!(
            file, scn,
            "{name}: scenarios/{name}.toml differs from the built-in"
        );
    }
}

#[test]
fn bad_scenario_files_get_clear_errors() {
    let s2 = std::fs::read_to_string(path("s2")).unwrap();
    let e = parse_scenario(&s2.replace("duration_s = ", "duration_s = \"x\" #")).unwrap_err();
    assert!(format!("{e:#}").contains("duration_s"), "{e:#}");
    let e = parse_scenario(&s2.replacen("channel = 0", "channel = 9", 1)).unwrap_err();
    assert!(format!("{e:#}").contains("channel must be 0–5"), "{e:#}");
    let e = parse_scenario("profile = \"boat\"").unwrap_err();
    assert!(
        format!("{e:#}").contains("boat") || format!("{e:#}").contains("missing"),
        "{e:#}"
    );
}

#[test]
fn unbounded_numbers_are_refused_by_field_before_anything_runs() {
    let s2 = std::fs::read_to_string(path("s2")).unwrap();
    let dur = |v: &str| s2.replace("duration_s = 65.0", &format!("duration_s = {v}"));
    assert_ne!(dur("1"), s2, "s2.toml has duration_s = 65.0");
    for (text, field) in [
        (dur("1e12"), "duration_s"),
        (dur("inf"), "duration_s"),
        (dur("nan"), "duration_s"),
        (dur("-5.0"), "duration_s"),
        (
            s2.replace("imu_rate_hz = 100.0", "imu_rate_hz = 1e15"),
            "imu_rate_hz",
        ),
        (
            s2.replace("duration_s = 65.0", "duration_s = 900000.0")
                .replace("imu_rate_hz = 100.0", "imu_rate_hz = 90000.0"),
            "duration_s × imu_rate_hz",
        ),
        (
            s2.replacen("start = ", "start = -inf #", 1),
            "faults[0].start",
        ),
        (
            s2.replacen("sign = ", "sign = 1e300 #", 1),
            "faults[0].sign",
        ),
    ] {
        let e = format!("{:#}", parse_scenario(&text).unwrap_err());
        assert!(e.contains(field), "{field}: {e}");
    }
    let dir = std::env::temp_dir().join(format!("imu-fdi-scn-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("huge.toml");
    std::fs::write(&f, dur("1e12")).unwrap();
    let e = format!("{:#}", read_scenario(&f).unwrap_err());
    assert!(
        e.contains("huge.toml") && e.contains("duration_s = 1000000000000"),
        "{e}"
    );
}
