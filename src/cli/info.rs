//! `caustics info` and `caustics render --technique list`.

use caustics::techniques;
use caustics::vk::Context;

pub fn info() -> anyhow::Result<()> {
    let devices = Context::list_devices()?;
    if devices.is_empty() {
        anyhow::bail!(
            "no Vulkan device found; install Mesa's lavapipe: apt-get install mesa-vulkan-drivers"
        );
    }
    for d in devices {
        println!(
            "[{}] {} ({:?}), Vulkan {}.{}.{}, {}",
            d.index,
            d.name,
            d.kind,
            d.api_version.0,
            d.api_version.1,
            d.api_version.2,
            d.driver.trim()
        );
        for (f, ok) in &d.features {
            println!("    {} {}", if *ok { "yes" } else { "NO " }, f.name());
        }
    }
    Ok(())
}

pub fn list_techniques() {
    println!("techniques (caustics render --technique NAME):");
    for t in techniques::TECHNIQUES {
        println!("  {:<14} {}", t.name, t.description);
        let components: Vec<_> = t.components.iter().map(|c| c.name()).collect();
        println!("      --component {}|all", components.join("|"));
        for p in t.params() {
            println!(
                "      --param {}=VALUE  {} [{} .. {}], default {}{}",
                p.name,
                p.description,
                p.min,
                p.max,
                p.default,
                match p.apply {
                    caustics::params::Apply::Live => " (live)",
                    caustics::params::Apply::Rebuild => "",
                }
            );
        }
    }
    println!(
        "  {:<14} ground-truth light tracer: run `caustics reference`",
        "reference"
    );
}
