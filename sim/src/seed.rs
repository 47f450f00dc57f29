//! One source of randomness: the scenario's seed, split into named sub-streams, so that adding a sensor or an
//! obstacle does not change the noise of another.

use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// The random generator of every sub-stream: xoshiro256++, a fixed, documented algorithm, so results do not
/// change with the `rand` crate's choice of default generator.
pub type Stream = Xoshiro256PlusPlus;

/// The sub-stream `name` of `seed` (for example `"odometry"`, `"bush/3"`, `"sensor/laser_left"`).
pub fn stream(seed: u64, name: &str) -> Stream {
    // FNV-1a of the name, mixed with the seed by SplitMix64 so nearby seeds give unrelated streams.
    let h = oeg_files::fnv1a64(name.as_bytes());
    let mut z = seed.wrapping_add(h).wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    Stream::seed_from_u64(z ^ (z >> 31))
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a: u64 = stream(7, "odometry").random();
        let b: u64 = stream(7, "odometry").random();
        let c: u64 = stream(7, "bush/0").random();
        let d: u64 = stream(8, "odometry").random();
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert_ne!(a, d);
    }
}
