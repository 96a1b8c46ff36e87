//! Typed `u32` handles into arenas.

/// Defines a `#[repr(transparent)]` `u32` id newtype; `Debug` prints `Name(3)`.
macro_rules! id_type {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
        #[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
        #[repr(transparent)]
        pub struct $name(u32);

        impl $name {
            /// The arena index.
            #[inline]
            pub const fn index(self) -> usize {
                self.0 as usize
            }

            /// Id 0.
            pub const ZERO: Self = $name(0);

            /// The id of arena index `i`; `None` beyond `u32`.
            #[inline]
            pub fn from_index(i: usize) -> Option<Self> {
                u32::try_from(i).ok().map($name)
            }
        }
    };
}

pub(crate) use id_type;
