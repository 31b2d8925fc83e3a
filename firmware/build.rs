//! Puts the board's `memory.x` on the linker's search path, where
//! cortex-m-rt's `link.x` includes it: the repository's (QEMU's mps2-an386,
//! the default) or, with a board feature, `boards/<board>/memory.x`.
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let dir = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let feature = |f: &str| std::env::var_os(format!("CARGO_FEATURE_{f}")).is_some();
    let memory = if feature("STM32F405") {
        dir.join("boards/stm32f405/memory.x")
    } else if feature("RP2040") {
        dir.join("boards/rp2040/memory.x")
    } else {
        dir.join("../memory.x")
    };
    std::fs::copy(&memory, out.join("memory.x")).expect("the board's memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", memory.display());
    if std::env::var_os("CARGO_FEATURE_DEFMT").is_some() {
        println!("cargo:rustc-link-arg=-Tdefmt.x");
    }
}
