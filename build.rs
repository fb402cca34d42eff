fn main() {
    if std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() == Ok("avr") {
        let dir = std::env::var("CARGO_MANIFEST_DIR").unwrap();
        println!("cargo:rustc-link-arg-bins={dir}/memory.x");
        println!("cargo:rerun-if-changed=memory.x");
    }
}
