//! The example scenarios bundled into the binary (the files of `examples/`).

/// `(name, text)` of every bundled example.
pub const ALL: &[(&str, &str)] = &[
    (
        "fabric-on-pedestal",
        include_str!("../../../examples/fabric-on-pedestal.toml"),
    ),
    (
        "fabric-on-pedestal-lagrange",
        include_str!("../../../examples/fabric-on-pedestal-lagrange.toml"),
    ),
    (
        "drape-tester",
        include_str!("../../../examples/drape-tester.toml"),
    ),
    (
        "drape-tester-static",
        include_str!("../../../examples/drape-tester-static.toml"),
    ),
    (
        "woven-drape-tester",
        include_str!("../../../examples/woven-drape-tester.toml"),
    ),
    (
        "bias-strip",
        include_str!("../../../examples/bias-strip.toml"),
    ),
    (
        "pedestal-fine",
        include_str!("../../../examples/pedestal-fine.toml"),
    ),
    (
        "hanging-cloth",
        include_str!("../../../examples/hanging-cloth.toml"),
    ),
    (
        "inflated-disc",
        include_str!("../../../examples/inflated-disc.toml"),
    ),
    (
        "folding-cloth",
        include_str!("../../../examples/folding-cloth.toml"),
    ),
    ("balloon", include_str!("../../../examples/balloon.toml")),
    ("cushion", include_str!("../../../examples/cushion.toml")),
    (
        "folded-bag",
        include_str!("../../../examples/folded-bag.toml"),
    ),
];
