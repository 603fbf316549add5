//! MAVLink's checksum (CRC-16/MCRF4XX, the X.25 polynomial reflected) with a table built at
//! compile time: the `mavlink` crate's generic CRC was a quarter of the telemetry encoding time.

const fn table() -> [u16; 256] {
    let mut t = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = i as u16;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0x8408
            } else {
                crc >> 1
            };
            bit += 1;
        }
        t[i] = crc;
        i += 1;
    }
    t
}

static TABLE: [u16; 256] = table();

/// The running checksum of `parts` in order, then the message's CRC_EXTRA byte.
pub(crate) fn checksum(parts: &[&[u8]], extra_crc: u8) -> u16 {
    let mut crc: u16 = 0xFFFF;
    for part in parts {
        for &b in *part {
            crc = (crc >> 8) ^ TABLE[usize::from((crc ^ u16::from(b)) as u8)];
        }
    }
    (crc >> 8) ^ TABLE[usize::from((crc ^ u16::from(extra_crc)) as u8)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn matches_the_mavlink_crate(data in prop::collection::vec(any::<u8>(), 0..300), extra: u8, cut in 0usize..300) {
            let cut = cut.min(data.len());
            prop_assert_eq!(
                checksum(&[&data[..cut], &data[cut..]], extra),
                mavlink::calculate_crc(&data, extra)
            );
        }
    }

    #[test]
    fn check_value_of_the_standard_string() {
        // CRC-16/MCRF4XX of "123456789" is 0x6F91; the extra byte here is the last digit.
        assert_eq!(checksum(&[b"12345678"], b'9'), 0x6F91);
    }
}
