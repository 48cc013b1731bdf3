//! The README's sample output is the program's: the quickstart command is run and its
//! table compared line by line with the README (timings aside). `COAGULA_BLESS=1 cargo
//! test -p coagula-cli --test readme` writes the fresh output into the README instead.

mod common;

use common::{coagula, succeeded};
use std::path::Path;

/// The shell command of the block before `prints`, and the output block after it:
/// `(command, first line of the output, one past its last line)`.
fn sample(readme: &str) -> (String, usize, usize) {
    let lines: Vec<&str> = readme.lines().collect();
    let at = lines
        .iter()
        .position(|l| l.starts_with("prints ("))
        .expect("the README has a sample after `prints (`");
    let cmd = lines[..at]
        .iter()
        .rev()
        .find(|l| l.starts_with("cargo run"))
        .expect("a command before the sample")
        .to_string();
    let open = at + lines[at..].iter().position(|l| *l == "```").unwrap() + 1;
    let close = open + lines[open..].iter().position(|l| *l == "```").unwrap();
    (cmd, open, close)
}

/// A line with its wall-clock and memory figures blanked.
fn untimed(l: &str) -> String {
    match l.find(" particle doublings; ") {
        Some(i) if l.starts_with("totals over") => l[..i].to_string(),
        _ => l.to_string(),
    }
}

#[test]
fn the_readme_sample_is_what_the_quickstart_prints() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../README.md");
    let readme = std::fs::read_to_string(&path).unwrap();
    let (cmd, open, close) = sample(&readme);
    let args: Vec<&str> = cmd
        .split_once(" -- ")
        .expect("cargo run ... -- ARGS")
        .1
        .split_whitespace()
        .collect();
    // the plot goes to a scratch file; the `wrote` line is compared by its name
    let plot_at = args.iter().position(|a| *a == "--plot").expect("--plot");
    let plot = args[plot_at + 1];
    assert!(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(plot)
            .exists(),
        "the README shows {plot}: it must be in the repository"
    );
    let scratch = std::env::temp_dir().join(format!("coagula-readme-{}.png", std::process::id()));
    let mut run: Vec<String> = args.iter().map(|s| s.to_string()).collect();
    run[plot_at + 1] = scratch.display().to_string();
    let out = coagula().args(&run).arg("--quiet").output().unwrap();
    succeeded(&out);
    std::fs::remove_file(&scratch).ok();
    let fresh: Vec<String> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| l.replace(&scratch.display().to_string(), plot))
        .collect();
    let lines: Vec<&str> = readme.lines().collect();
    let shown = &lines[open..close];
    if std::env::var_os("COAGULA_BLESS").is_some() {
        let mut text: Vec<String> = lines[..open].iter().map(|s| s.to_string()).collect();
        text.extend(fresh.iter().cloned());
        text.extend(lines[close..].iter().map(|s| s.to_string()));
        std::fs::write(&path, text.join("\n") + "\n").unwrap();
        return;
    }
    let a: Vec<String> = shown.iter().map(|l| untimed(l)).collect();
    let b: Vec<String> = fresh.iter().map(|l| untimed(l)).collect();
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert_eq!(
            x,
            y,
            "README line {} differs (COAGULA_BLESS=1 rewrites it)",
            open + i + 1
        );
    }
    assert_eq!(
        a.len(),
        b.len(),
        "README sample length (COAGULA_BLESS=1 rewrites it)"
    );
}
