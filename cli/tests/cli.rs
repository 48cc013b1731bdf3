//! End-to-end tests of the `coagula` binary.

use std::process::Command;

fn coagula() -> Command {
    Command::new(env!("CARGO_BIN_EXE_coagula"))
}

/// `coagula run` writes the documented CSV, and its moments are those of the exact
/// solution to QMC accuracy (N = 2^10, P = 100: errors ~1e-3, far below a factor-2 bug).
#[test]
fn run_writes_csv_close_to_exact() {
    let dir = std::env::temp_dir().join(format!("coagula-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("run.csv");
    let svg = dir.join("run.svg");
    let out = coagula()
        .args(["run", "--m", "10", "--steps", "100", "--csv"])
        .arg(&csv)
        .arg("--plot")
        .arg(&svg)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "t,M2,M2_exact,M3,M3_exact");
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 100);
    for r in &rows {
        let t = r[0];
        let m2 = 3.0 - 2.0 * (-t / 3.0f64).exp();
        let m3 = 18.0 - 36.0 * (-t / 3.0f64).exp() + 19.0 * (-t / 2.0f64).exp();
        assert!(
            (r[2] - m2).abs() < 1e-12 && (r[4] - m3).abs() < 1e-12,
            "exact columns"
        );
        assert!((r[1] - m2).abs() < 0.01 * m2, "t={t}: M2 {} vs {m2}", r[1]);
        assert!((r[3] - m3).abs() < 0.02 * m3, "t={t}: M3 {} vs {m3}", r[3]);
    }
    let svg_text = std::fs::read_to_string(&svg).unwrap();
    assert!(svg_text.starts_with("<svg"), "an SVG");
    assert!(
        svg_text.contains("M2(t)") && svg_text.contains("M3 − exact"),
        "panels"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_arguments_fail_with_a_message() {
    let out = coagula()
        .args(["run", "--m", "10", "--steps", "100", "--plot", "x.pdf"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains(".svg or .png"));
    assert!(
        !std::path::Path::new("x.pdf").exists(),
        "refused before any file is made"
    );
    let out = coagula().args(["run", "--m", "0"]).output().unwrap();
    assert!(!out.status.success());
    let out = coagula().args(["exact", "--times=-1"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("t = -1"));
}

/// Issue 15's list of inputs that panicked or ran meaninglessly: each is now refused
/// with a message and a failing exit status, and none panics.
#[test]
fn bad_input_is_refused_without_a_panic() {
    let cases: &[&[&str]] = &[
        &["qmc", "--m", "65"],
        &["qmc", "--dims", "0"],
        &["bench", "lowrank", "--n0", "0"],
        &["bench", "lowrank", "--only", "foo"],
        &["bench", "lowrank-single", "--n0", "0"],
        &["bench", "lowrank-single", "--t=-1"],
        &["bench", "lowrank-single", "--t", "nan"],
        &["bench", "lowrank-single", "--kernel", "foo"],
        &["kernels", "--points", "0"],
        &["kernels", "--min", "0"],
        &["kernels", "--min", "10", "--max", "5"],
        &["reproduce", "lecot2019", "--m-max", "3"],
        &["reproduce", "lecot2019", "--mc-seeds", "0"],
        &["reproduce", "lecot2019", "--rqmc", "1"],
        &["exact", "--times", "-1"],
        &["run", "--steps", "1"],
        &["run", "--m", "6", "--csv", "/nonexistent/dir/x.csv"],
        &["run", "--m", "6", "--plot", "/nonexistent/dir/x.svg"],
    ];
    for args in cases {
        let out = coagula().args(*args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
        assert!(err.contains("error"), "{args:?}: no error message: {err}");
    }
}

/// `--csv -` writes the CSV to standard output (the table moves to standard error).
#[test]
fn run_csv_to_standard_output() {
    let out = coagula()
        .args(["run", "--m", "6", "--steps", "100", "--csv", "-"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,M2,M2_exact,M3,M3_exact"));
    assert_eq!(lines.count(), 100);
    assert!(String::from_utf8_lossy(&out.stderr).contains("M2 exact"));
    assert!(!std::path::Path::new("-").exists(), "no file named '-'");
}
