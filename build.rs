//! Link the defmt section script into the firmware binary only (the
//! software-in-the-loop image in hal-sim logs over semihosting without defmt).
fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let bare_metal = std::env::var("CARGO_CFG_TARGET_OS").is_ok_and(|os| os == "none");
    if bare_metal && std::env::var_os("CARGO_FEATURE_FIRMWARE").is_some() {
        println!("cargo:rustc-link-arg-bin=firmware=-Tdefmt.x");
    }
}
