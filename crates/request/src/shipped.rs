//! The sensor models shipped in configs/sensors, built into the program (no imports: the error
//! texts and the file readers both name them).

/// The sensor models shipped in configs/sensors (name, TOML text), addressable by name wherever a
/// sensor file is read ([`crate::files::read_config`]).
pub const SHIPPED_SENSORS: [(&str, &str); 5] = [
    (
        "adis16405",
        include_str!("../../../configs/sensors/adis16405.toml"),
    ),
    (
        "bmi088",
        include_str!("../../../configs/sensors/bmi088.toml"),
    ),
    (
        "gg1320an",
        include_str!("../../../configs/sensors/gg1320an.toml"),
    ),
    (
        "gg5300",
        include_str!("../../../configs/sensors/gg5300.toml"),
    ),
    ("mtx", include_str!("../../../configs/sensors/mtx.toml")),
];
