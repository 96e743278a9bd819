//! Print the built-in default material as RON: `cargo run -p lodestone-core --example default_preset > presets/default.ron`.

fn main() {
    println!("{}", lodestone_core::material::Material::default().to_ron());
}
