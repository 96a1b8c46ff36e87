//! Generated from `std-demo/scenes/hall.json` by
//! `cargo test -p vcx-tests --test no_alloc -- --ignored regenerate_firmware_data`;
//! do not edit (`firmware_viewpoints_are_fresh` checks it). The viewpoints the firmware
//! walks: what the `.vcx` file cannot hold. Not formatted (`#[rustfmt::skip]` where it is
//! declared).

/// Viewpoints (raw query coordinates, 2⁻³²).
pub static VIEWPOINTS: [(i64, i64); 6] = [
    (15461894610, 50680607303),
    (15461894610, 85899339131),
    (15461894610, 121118070958),
    (15461894610, 156336802785),
    (50680626437, 15461875476),
    (50680626437, 50680607303),
];
