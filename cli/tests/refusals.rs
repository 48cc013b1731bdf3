//! The `coagula` binary refuses bad input — arguments, scenarios, hostile and fuzzed
//! files — with a message and exit status 1 or 2, never a panic.

mod common;

use common::{coagula, examples, succeeded};

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

/// Bad scenarios fail with exit status 1 and a message naming the key and its line.
#[test]
fn bad_scenarios_name_the_key_and_line() {
    let dir = std::env::temp_dir().join(format!("coagula-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = "title = \"t\"\n[kernel]\nkind = \"constant\"\n[initial]\nkind = \"monodisperse\"\nparticles = 1000\n[scheme]\nname = \"lowrank\"\n[output]\ntimes = [1.0]\nobservables = [\"M0\"]\n";
    let cases: &[(&str, &str, &str)] = &[
        (
            "kind = \"constant\"",
            "kind = \"constant\"\ncoefficent = 2",
            ":4: kernel.coefficent",
        ),
        ("particles = 1000", "particles = \"many\"", "line 6"),
        (
            "kind = \"constant\"",
            "kind = \"product\"\na = 1.5",
            ":4: kernel.a",
        ),
        (
            "kind = \"constant\"",
            "kind = \"constant\"\na = 0.5",
            ":4: kernel.a",
        ),
        ("particles = 1000", "particles = 1", ":6: initial.particles"),
        (
            "name = \"lowrank\"",
            "name = \"lowrnak\"",
            ":8: scheme.name",
        ),
        (
            "name = \"lowrank\"",
            "name = \"lowrank\"\ndt = 0.1",
            ":9: scheme.dt",
        ),
        ("times = [1.0]", "times = [1.0, 0.5]", ":10: output.times"),
        ("times = [1.0]", "times = [-1.0]", ":10: output.times"),
        ("[\"M0\"]", "[\"M0\", \"Q7\"]", ":11: output.observables"),
        ("[\"M0\"]", "[]", ":11: output.observables"),
        (
            "title = \"t\"",
            "title = \"t\"\n[fragmentation]\nkind = \"binary-uniform\"",
            "fragmentation",
        ),
        (
            "name = \"lowrank\"",
            "name = \"massflow\"\ndt = 0.5",
            "power of two",
        ),
        (
            "kind = \"constant\"",
            "kind = \"constant\"\ncoefficient = nan",
            ":4: kernel.coefficient",
        ),
        (
            "kind = \"constant\"",
            "kind = \"brownian-continuum\"\ntemperature = 300",
            "kernel.viscosity",
        ),
        (
            "particles = 1000",
            "particles = 1000\nconcentration = 0",
            ":7: initial.concentration",
        ),
        (
            "[output]",
            "[run]\nreplicas = 0\n[output]",
            ":10: run.replicas",
        ),
        ("[output]", "[outptu]\nx = 1\n[output]", "outptu"),
        (
            "particles = 1000",
            "particles = 1000000000000",
            "initial particle number",
        ),
    ];
    for (i, (from, to, want)) in cases.iter().enumerate() {
        assert!(good.contains(from), "{from}");
        let text = good.replacen(from, to, 1);
        let path = dir.join(format!("bad{i}.toml"));
        std::fs::write(&path, &text).unwrap();
        let out = coagula()
            .arg("run")
            .arg(&path)
            .arg("--quiet")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{text}\n{err}");
        assert!(err.contains("error"), "{text}: {err}");
        assert!(err.contains(want), "{text}: want {want:?} in {err}");
    }
    // flags and other inputs
    let flags: &[&[&str]] = &[
        &["run", "no-such-scenario"],
        &["run", "--set", "nokey"],
        &["run", "--set", "kernel.coefficient=-1"],
        &["run", "--scheme", "foo"],
        &["run", "--csv", "-", "--json", "-"],
        &["run", "--json", "/nonexistent/dir/x.json"],
        &["run", "quickstart-constant", "--steps", "10"],
        &["run", "--points", "qmc", "--replicas", "3"],
        &["run", "--particles", "1000"],
        &["run", "--threads", "5000"],
        &["examples", "nope"],
        &["bench", "scenario", "--schemes", "foo"],
        &["bench", "scenario", "--vary", "x"],
        &["exact", "--solution", "golovin", "--x", "0"],
    ];
    for args in flags {
        let out = coagula().args(*args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        let code = out.status.code();
        assert!(
            matches!(code, Some(1) | Some(2)),
            "{args:?}: {code:?} {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(err.contains("error"), "{args:?}: {err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A fuzzed corpus: every example mutated 40 ways (numbers replaced by hostile values,
/// lines deleted, duplicated, swapped, truncated, bytes inserted) and checked with
/// `--check`; the CLI exits 0, 1 or 2, never with a panic (101) or a signal.
#[test]
fn fuzzed_scenarios_never_panic() {
    const NASTY: &[&str] = &[
        "0",
        "-1",
        "nan",
        "inf",
        "-inf",
        "1e308",
        "1e-308",
        "5e-324",
        "18446744073709551615",
        "9223372036854775807",
        "4294967297",
        "\"x\"",
        "[]",
        "{}",
        "true",
        "2.5",
        "[1.0, -1]",
        "1e300",
        "0.0",
        "-0.0",
    ];
    let dir = std::env::temp_dir().join(format!("coagula-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut count = 0;
    for path in examples() {
        let text = std::fs::read_to_string(&path).unwrap();
        for k in 0..40 {
            let mut lines: Vec<String> = text.lines().map(String::from).collect();
            for _ in 0..1 + next() % 3 {
                let n = lines.len().max(1);
                let i = (next() as usize) % n;
                match next() % 6 {
                    0 => {
                        // replace the value of a key line
                        if let Some(eq) = lines[i].find('=') {
                            let v = NASTY[(next() as usize) % NASTY.len()];
                            lines[i] = format!("{}= {v}", &lines[i][..eq]);
                        }
                    }
                    1 => {
                        lines.remove(i);
                    }
                    2 => {
                        let l = lines[i].clone();
                        lines.insert(i, l);
                    }
                    3 => {
                        let j = (next() as usize) % n;
                        lines.swap(i, j);
                    }
                    4 => lines.truncate(i),
                    _ => {
                        let c = char::from(b' ' + (next() % 95) as u8);
                        let at = (next() as usize) % (lines[i].len() + 1);
                        if lines[i].is_char_boundary(at) {
                            lines[i].insert(at, c);
                        }
                    }
                }
                if lines.is_empty() {
                    break;
                }
            }
            let file = dir.join(format!("f{count}.toml"));
            std::fs::write(&file, lines.join("\n")).unwrap();
            let out = coagula()
                .arg("run")
                .arg(&file)
                .arg("--check")
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(
                matches!(out.status.code(), Some(0..=2)),
                "{} (mutation {k}): {:?}\n{err}\n{}",
                path.display(),
                out.status,
                lines.join("\n")
            );
            assert!(!err.contains("panicked"), "{err}");
            if !out.status.success() {
                assert!(err.contains("error"), "{err}");
            }
            count += 1;
        }
    }
    assert!(count >= 400);
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 40: counts accept `1e6`-style input wherever a count is asked for, and refuse
/// negatives and fractions with a message of ours (not clap's tip about `--`).
#[test]
fn counts_accept_exponent_notation() {
    let out = coagula()
        .args([
            "run",
            "quickstart-constant",
            "--particles",
            "2e3",
            "--quiet",
        ])
        .output()
        .unwrap();
    succeeded(&out);
    for (flag, bad, says) in [
        ("--particles", "-1", "-1 is not a count"),
        ("--particles", "1.5", "1.5 is not a count"),
        ("--replicas", "2e9", "outside [1, 1000000]"),
    ] {
        let out = coagula()
            .args(["run", "quickstart-constant", flag, bad])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{flag} {bad} accepted");
        assert!(err.contains(says), "{flag} {bad}: {err}");
        assert!(!err.contains("'-- "), "{flag} {bad}: clap's tip: {err}");
    }
    // and in a scenario
    let out = coagula()
        .args([
            "run",
            "quickstart-constant",
            "--particles",
            "1e3",
            "--quiet",
        ])
        .args(["--set", "run.replicas=2e0"])
        .output()
        .unwrap();
    succeeded(&out);
    let out = coagula()
        .args(["run", "quickstart-constant", "--set", "run.replicas=1.5"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("1.5 is not a count"),
        "{err}"
    );
    let out = coagula()
        .args(["bench", "lowrank-small", "--n0", "1"])
        .output()
        .unwrap();
    assert!(!out.status.success(), "N0 = 1 has no events to time");
}

/// Issue 40: `exact` at large times printed M3 = NaN (inf − inf) and 300-digit
/// decimals; `--x` on a solution over integer sizes printed nothing and exited 0.
#[test]
fn exact_prints_large_values_readably_and_refuses_missing_columns() {
    let out = coagula()
        .args(["exact", "--solution", "golovin", "--times", "300,1e300"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.contains("NaN"), "{text}");
    assert!(text.lines().all(|l| l.len() < 120), "{text}");
    assert!(text.contains("7.546040601859879e260"), "{text}");
    for args in [
        ["exact", "--solution", "constant", "--x", "1,2"],
        ["exact", "--solution", "golovin", "--kmax", "3"],
    ] {
        let out = coagula().args(args).output().unwrap();
        assert!(!out.status.success(), "{args:?} accepted");
        assert!(String::from_utf8_lossy(&out.stderr).contains("ask for"));
    }
}

/// The review's inputs that failed only after the run had started (issue 40) are
/// refused or warned about before any work: a Golovin run whose size tables would pass
/// the memory budget (t-end = 50, 1e300), a write to a full device names its target,
/// and a run far past the gel point is warned about.
#[test]
fn growth_and_outputs_are_checked_before_the_run() {
    for t in ["50", "1e300"] {
        let out = coagula()
            .args(["run", "quickstart-golovin", "--check", "--set"])
            .arg(format!("output.t-end={t}"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "t-end {t} accepted");
        assert!(
            err.contains("output.t-end") && err.contains("memory budget"),
            "t-end {t}: {err}"
        );
    }
    // a reachable end passes the check
    let out = coagula()
        .args([
            "run",
            "quickstart-golovin",
            "--check",
            "--set",
            "output.t-end=2",
        ])
        .output()
        .unwrap();
    succeeded(&out);
    if std::path::Path::new("/dev/full").exists() {
        for flag in ["--csv", "--json"] {
            let out = coagula()
                .args([
                    "run",
                    "--m",
                    "8",
                    "--steps",
                    "100",
                    "--quiet",
                    flag,
                    "/dev/full",
                ])
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(!out.status.success());
            assert!(err.contains(&format!("{flag} /dev/full:")), "{err}");
        }
    }
    // (t = 13 is now refused: the gel, which particle doubling doubles with the
    // volume, would pass 1e10 monomers and its size table the memory budget)
    let out = coagula()
        .args([
            "run",
            "multiplicative-gelation",
            "--check",
            "--set",
            "output.times=[0.5, 6.0]",
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    assert!(
        text.contains("warning: the run goes past the gel point t = 1"),
        "{text}"
    );
    let out = coagula()
        .args(["run", "multiplicative-gelation", "--check"])
        .output()
        .unwrap();
    assert!(!String::from_utf8_lossy(&out.stdout).contains("warning"));
}

/// The default run (Lécot et al. 2019 §4 at P = 800) clips no probability, and a
/// mass-flow table says that its error holds the time-step bias.
#[test]
fn the_default_run_does_not_clip() {
    let out = coagula().args(["run", "--quiet"]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    succeeded(&out);
    assert!(text.contains("(0 rejected), 0 clipped"), "{text}");
    assert!(text.contains("O(dt) time-step bias"), "{text}");
}

/// Size classes that are not strictly increasing sizes > 0 are refused by name.
#[test]
fn bad_size_classes_are_refused() {
    for bad in ["[2.0, 1.0]", "[1.0]", "[0.0, 1.0]", "[1.0, 1.0, 2.0]"] {
        let out = coagula()
            .args(["run", "quickstart-constant", "--check", "--set"])
            .arg(format!("output.classes={bad}"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains("output.classes"),
            "{bad}: {err}"
        );
    }
    let out = coagula()
        .args([
            "run",
            "quickstart-constant",
            "--check",
            "--set",
            "output.classes=[0.5, 1.5, 10.5]",
        ])
        .output()
        .unwrap();
    succeeded(&out);
}

/// A file with several mistakes is told of each at once (issue 40: only the first was).
#[test]
fn every_independent_error_of_a_file_is_reported() {
    let dir = std::env::temp_dir().join(format!("coagula-errs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("bad.toml");
    std::fs::write(
        &f,
        "[kernel]\nkind = \"product\"\na = 1.5\n\n[initial]\nkind = \"monodisperse\"\nparticles = 1000\n\n\
         [scheme]\nname = \"lowrank\"\n\n[output]\ntimes = [1.0, 0.5]\nobservables = [\"M0\", \"Q7\"]\n\n\
         [run]\nreplicas = 0\n",
    )
    .unwrap();
    let out = coagula().args(["run", "--check"]).arg(&f).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("4 errors"), "{err}");
    for (line, key) in [
        (3, "kernel.a"),
        (13, "output.times"),
        (14, "output.observables"),
        (17, "run.replicas"),
    ] {
        assert!(
            err.contains(&format!("bad.toml:{line}: {key}:")),
            "{key}: {err}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `reproduce lecot2019 --quick` is refused (it has no quick form), not ignored, and a
/// part it does not have is named.
#[test]
fn lecot2019_refuses_quick_and_unknown_parts() {
    let out = coagula()
        .args(["reproduce", "lecot2019", "--quick"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--quick"));
    let out = coagula()
        .args(["reproduce", "lecot2019", "--figures", "fig9"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("dt-ladder"));
}
