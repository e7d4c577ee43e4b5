//! Owen-scrambled, shuffled 2D Sobol' points (Burley, "Practical Hash-based Owen Scrambling",
//! JCGT 2020): the numbers of [`Sampler`](super::Sampler)'s `sobol` kind.
//!
//! The first dimension of the Sobol' sequence is the bit reversal of the index; the second is
//! the XOR of direction numbers of the index's set bits, read from tables a byte at a time.
//! Laine and Karras' hash permutes the bits of a fixed-point number from high to low so that
//! each bit's flip depends only on the bits above it: a nested uniform (Owen) scramble. A point
//! set is shuffled (its index scrambled) and each coordinate scrambled, each with its own seed.
//! [`shuffled_scrambled_sobol_2d`] is the fast form; Burley's listing as written is its twin,
//! and a test compares them bit for bit.

/// The second dimension of the Sobol' sequence (the first is the bit reversal of the index),
/// as 32-bit fixed point: the XOR of the direction numbers of the index's set bits, a byte of
/// the index at a time from tables (no branch per bit).
#[cfg(test)]
fn sobol_second_dimension(index: u32) -> u32 {
    let [b0, b1, b2, b3] = index.to_le_bytes();
    SOBOL_SECOND_DIMENSION[0][b0 as usize]
        ^ SOBOL_SECOND_DIMENSION[1][b1 as usize]
        ^ SOBOL_SECOND_DIMENSION[2][b2 as usize]
        ^ SOBOL_SECOND_DIMENSION[3][b3 as usize]
}

/// `SOBOL_SECOND_DIMENSION[k][b]`: the XOR of the direction numbers of bits `8k..8k+8` set in `b`.
static SOBOL_SECOND_DIMENSION: [[u32; 256]; 4] = sobol_second_dimension_tables();

/// The tables, built at compile time from the direction numbers `v₀ = 2³¹`, `vₖ = vₖ₋₁ ⊕ (vₖ₋₁ ≫ 1)`.
const fn sobol_second_dimension_tables() -> [[u32; 256]; 4] {
    let mut directions = [0u32; 32];
    directions[0] = 1 << 31;
    let mut k = 1;
    while k < 32 {
        directions[k] = directions[k - 1] ^ (directions[k - 1] >> 1);
        k += 1;
    }
    let mut tables = [[0u32; 256]; 4];
    let mut byte = 0;
    while byte < 4 {
        let mut value = 0;
        while value < 256 {
            let mut result = 0;
            let mut bit = 0;
            while bit < 8 {
                if value & (1 << bit) != 0 {
                    result ^= directions[byte * 8 + bit];
                }
                bit += 1;
            }
            tables[byte][value] = result;
            value += 1;
        }
        byte += 1;
    }
    tables
}

/// Laine and Karras' hash-based permutation of the bits of `x` from high to low, each bit's flip
/// depending only on the bits below it (in reversed order: a nested uniform scramble).
#[inline]
pub(super) fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// An Owen scramble of a 32-bit fixed-point number (Burley 2020, listing 3).
#[cfg(test)]
fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// Point `index` of a 2D Sobol' set whose order is shuffled and whose coordinates are
/// Owen-scrambled, each by its own seed (Burley 2020, listing 5), given `index` bit-reversed.
///
/// The same bits as `shuffled_scrambled_sobol_2d_reference` (tested), with three bit reversals
/// where the listing has five, two of them done as one 64-bit reversal: the shuffled index's
/// reversal is the permutation's input as it stands, and the second dimension's reversal is read
/// from a table of reversed direction numbers indexed by the permuted bits directly.
#[inline]
pub(super) fn shuffled_scrambled_sobol_2d(
    reversed_index: u32,
    [shuffle, seed_x, seed_y]: [u32; 3],
) -> [u32; 2] {
    // nested_uniform_scramble(index, shuffle) = reverse(permuted).
    let permuted = laine_karras_permutation(reversed_index, shuffle);
    let index = permuted.reverse_bits();
    let [b0, b1, b2, b3] = permuted.to_le_bytes();
    // reverse(sobol_second_dimension(index)).
    let y_reversed = SOBOL_SECOND_DIMENSION_REVERSED[0][b0 as usize]
        ^ SOBOL_SECOND_DIMENSION_REVERSED[1][b1 as usize]
        ^ SOBOL_SECOND_DIMENSION_REVERSED[2][b2 as usize]
        ^ SOBOL_SECOND_DIMENSION_REVERSED[3][b3 as usize];
    let x = laine_karras_permutation(index, seed_x);
    let y = laine_karras_permutation(y_reversed, seed_y);
    // reverse(x) in the low half, reverse(y) in the high half.
    let both = ((x as u64) << 32 | y as u64).reverse_bits();
    [both as u32, (both >> 32) as u32]
}

/// Burley's listing 5 as written, the twin of [`shuffled_scrambled_sobol_2d`].
#[cfg(test)]
fn shuffled_scrambled_sobol_2d_reference(
    index: u32,
    [shuffle, seed_x, seed_y]: [u32; 3],
) -> [u32; 2] {
    let index = nested_uniform_scramble(index, shuffle);
    // x = reverse(index) scrambled: reverse(LK(reverse(reverse(index)))) = reverse(LK(index)).
    let x = laine_karras_permutation(index, seed_x).reverse_bits();
    let y = nested_uniform_scramble(sobol_second_dimension(index), seed_y);
    [x, y]
}

/// `SOBOL_SECOND_DIMENSION_REVERSED[k][b]`: `reverse(sobol_second_dimension(reverse(w)))` for the
/// word `w` whose byte `k` is `b` and whose other bytes are zero, so that for any `w` it is the
/// XOR of the entries of `w`'s four bytes.
static SOBOL_SECOND_DIMENSION_REVERSED: [[u32; 256]; 4] = sobol_second_dimension_reversed_tables();

const fn sobol_second_dimension_reversed_tables() -> [[u32; 256]; 4] {
    let mut tables = [[0u32; 256]; 4];
    let mut byte = 0;
    while byte < 4 {
        let mut value = 0;
        while value < 256 {
            // Byte `byte` of w reversed is byte `3 - byte` of reverse(w), its bits reversed.
            let reversed = (value as u8).reverse_bits() as usize;
            tables[byte][value] = SOBOL_SECOND_DIMENSION[3 - byte][reversed].reverse_bits();
            value += 1;
        }
        byte += 1;
    }
    tables
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;

    #[test]
    fn the_second_sobol_dimension_tables_equal_the_bit_by_bit_definition() {
        let bit_by_bit = |mut index: u32| {
            let (mut v, mut result) = (1u32 << 31, 0);
            while index != 0 {
                if index & 1 != 0 {
                    result ^= v;
                }
                index >>= 1;
                v ^= v >> 1;
            }
            result
        };
        let mut rng = Pcg32::new(5, 6);
        for index in (0..4096).chain((0..10_000).map(|_| rng.next_u32())).chain([u32::MAX]) {
            assert_eq!(sobol_second_dimension(index), bit_by_bit(index), "{index}");
        }
    }

    #[test]
    fn the_fast_sobol_points_equal_burleys_listing() {
        let mut rng = Pcg32::new(8, 9);
        let mut indices: Vec<u32> = (0..2048).chain([u32::MAX]).collect();
        indices.extend((0..20_000).map(|_| rng.next_u32()));
        for i in indices {
            let seeds = [rng.next_u32(), rng.next_u32(), rng.next_u32()];
            assert_eq!(
                shuffled_scrambled_sobol_2d(i.reverse_bits(), seeds),
                shuffled_scrambled_sobol_2d_reference(i, seeds),
                "index {i}, seeds {seeds:?}"
            );
        }
    }

    #[test]
    fn the_second_sobol_dimension_is_the_known_sequence() {
        // Direction numbers 1/2, 3/4, 5/8, 15/16 (Joe and Kuo's dimension 2), combined by the
        // index's bits (not in Gray-code order): 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8, 15/16.
        let expected = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875, 0.9375];
        for (i, &e) in expected.iter().enumerate() {
            assert_eq!(sobol_second_dimension(i as u32) as f64 / 2f64.powi(32), e, "{i}");
        }
    }
}
