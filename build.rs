//! Tests that need the real IMU logs and the reference tables read them from the directory named by
//! `IMUDRIFT_DATA`. Without it they are compiled as ignored, with the reason, so `cargo test`
//! reports them as skipped rather than passing without checking anything.
fn main() {
    println!("cargo::rustc-check-cfg=cfg(imudrift_no_data)");
    println!("cargo::rerun-if-env-changed=IMUDRIFT_DATA");
    println!("cargo::rerun-if-changed=build.rs");
    let has_data =
        std::env::var_os("IMUDRIFT_DATA").is_some_and(|d| std::path::Path::new(&d).is_dir());
    if !has_data {
        println!("cargo::rustc-cfg=imudrift_no_data");
    }
}
