//! Passes the memory budgets (`memory.x`) to the AVR linker.
//!
//! `UTILE_MEMORY_X` names another file instead: `cargo fw --check-budget-enforced` links with
//! shrunken budgets that way to prove that an image over budget fails to link.

fn main() {
    println!("cargo:rerun-if-env-changed=UTILE_MEMORY_X");
    if std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() == Ok("avr") {
        let path = match std::env::var("UTILE_MEMORY_X") {
            Ok(path) if !path.is_empty() => path,
            _ => {
                let dir = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| ".".into());
                format!("{dir}/memory.x")
            }
        };
        println!("cargo:rustc-link-arg-bins={path}");
        println!("cargo:rerun-if-changed={path}");
    }
}
