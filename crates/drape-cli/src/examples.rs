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
        "bending-friction",
        include_str!("../../../examples/bending-friction.toml"),
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

/// The files an example reads beside it, `(example, path as its scenario
/// names it, contents)`: `drape example NAME --write FILE` writes them
/// beside FILE, so that the written scenario runs as it is.
pub const FILES: &[(&str, &str, &[u8])] = &[(
    "folded-bag",
    "meshes/folded-bag.obj",
    include_bytes!("../../../examples/meshes/folded-bag.obj"),
)];

/// The files `name` reads beside it ([`FILES`]).
pub fn files_of(name: &str) -> impl Iterator<Item = (&'static str, &'static [u8])> + '_ {
    FILES
        .iter()
        .filter(move |(n, _, _)| *n == name)
        .map(|(_, path, bytes)| (*path, *bytes))
}
