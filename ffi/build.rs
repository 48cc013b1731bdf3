//! Gives the shared library a SONAME (`libcoagula.so.MAJOR` on ELF platforms), so that
//! programs linked against it keep working across compatible upgrades and the installed
//! file can carry the full version (see scripts/install.sh).
fn main() {
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let major = std::env::var("CARGO_PKG_VERSION_MAJOR").unwrap_or_else(|_| "0".into());
    if matches!(
        os.as_str(),
        "linux" | "freebsd" | "netbsd" | "openbsd" | "dragonfly"
    ) {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libcoagula.so.{major}");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
