//! Writes a rig with a cage from the built-in lizard's outline (N vertices, default
//! 16): `cargo run --release -p pipeline --example lizard_cage -- [N] > RIG.json`,
//! for `c2warp bench --image assets/lizard.png --rig RIG.json`.

fn main() -> anyhow::Result<()> {
    let vertices = std::env::args()
        .nth(1)
        .and_then(|n| n.parse().ok())
        .unwrap_or(16);
    let image = image::load_from_memory(pipeline::DEFAULT_IMAGE)?.to_rgba8();
    let cage = pipeline::cage::cage_from_outline(&image, vertices, 6.0)?;
    let rest: Vec<String> = cage.iter().map(|p| format!("[{}, {}]", p.x, p.y)).collect();
    println!(
        r#"{{"version": 1, "method": "lbc", "handles": [], "cage": {{"rest": [{}]}}}}"#,
        rest.join(", ")
    );
    Ok(())
}
