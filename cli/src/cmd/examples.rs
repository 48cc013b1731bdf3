//! `coagula examples`: the built-in example scenarios, or one of them.

use crate::examples;

/// Lists the examples, or prints the one named.
pub fn command(name: Option<&str>) -> Result<(), String> {
    match name {
        None => {
            println!(
                "built-in example scenarios (coagula run NAME, coagula examples NAME to print one):"
            );
            for (file, text) in examples::EXAMPLES {
                let title = text
                    .lines()
                    .find_map(|l| l.strip_prefix("title = "))
                    .unwrap_or("")
                    .trim_matches('"');
                println!("  {:<42} {title}", file.trim_end_matches(".toml"));
            }
            Ok(())
        }
        Some(n) => match examples::get(n) {
            Some((_, text)) => {
                print!("{text}");
                Ok(())
            }
            None => Err(format!(
                "no example named {n:?} (coagula examples lists them)"
            )),
        },
    }
}
