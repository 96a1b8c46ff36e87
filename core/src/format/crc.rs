//! CRC-32/IEEE (the checksum of zip, PNG and Ethernet): reflected polynomial `0xEDB88320`,
//! initial value and final XOR `0xFFFFFFFF`. `crc32(b"123456789") == 0xCBF43926`.
//!
//! A 1 KiB table built at compile time; one lookup per byte. CRC-32 detects every
//! single-bit error and every burst of up to 32 bits, which is what a flash or a
//! transfer corrupts.

/// The byte-wise table of the reflected polynomial.
const TABLE: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
};

/// The CRC-32/IEEE of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        // The index is masked to 0..=255: always in the table.
        c = TABLE[((c ^ u32::from(b)) & 0xFF) as usize] ^ (c >> 8);
    }
    !c
}

#[cfg(test)]
mod tests {
    #[test]
    fn check_value() {
        assert_eq!(super::crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(super::crc32(b""), 0);
    }
}
