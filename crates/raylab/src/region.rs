//! Parts of an image: the rectangle of pixels one process renders when a render is split over
//! several (`raylab render --tile I/N` or `--region`), to be assembled by `raylab merge`.
//!
//! A [`Region`] is half-open, in pixels of the full image: `x0..x1` × `y0..y1`, `(0, 0)` the
//! top-left pixel. Every pixel's samples depend on (seed, pixel, sample index) alone, so a region
//! rendered on its own has exactly the pixels the full render has there, bit for bit.
//!
//! [`Region::tile`] cuts an image into `n` strips of whole rows whose heights differ by at most
//! one, the first `height mod n` strips one row taller. A 512-row image in 3 tiles:
//!
//! | tile | rows | height |
//! |---|---|---:|
//! | 0 | 0..171 | 171 |
//! | 1 | 171..342 | 171 |
//! | 2 | 342..512 | 170 |

/// Why a region or a tile cannot be rendered.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum RegionError {
    /// The rectangle is empty or reversed.
    #[error("region {0} is empty: it needs x0 < x1 and y0 < y1")]
    Empty(Region),
    /// The rectangle reaches outside the image.
    #[error("region {region} reaches outside the {width}×{height} image")]
    Outside {
        /// The rectangle asked for.
        region: Region,
        /// The image's width.
        width: u32,
        /// The image's height.
        height: u32,
    },
    /// The tile number is not below the tile count, or there are more tiles than rows.
    #[error("{reason}")]
    Tile {
        /// What is wrong, in words.
        reason: String,
    },
}

/// A rectangle of pixels, half-open: columns `x0..x1`, rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Region {
    /// The first column.
    pub x0: u32,
    /// The first row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl std::fmt::Display for Region {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

impl Region {
    /// The whole of a `width×height` image.
    pub fn full(width: u32, height: u32) -> Region {
        Region { x0: 0, y0: 0, x1: width, y1: height }
    }

    /// The rectangle `x0..x1` × `y0..y1`, checked to be non-empty and inside a `width×height`
    /// image.
    pub fn new([x0, y0, x1, y1]: [u32; 4], width: u32, height: u32) -> Result<Region, RegionError> {
        let region = Region { x0, y0, x1, y1 };
        if x0 >= x1 || y0 >= y1 {
            return Err(RegionError::Empty(region));
        }
        if x1 > width || y1 > height {
            return Err(RegionError::Outside { region, width, height });
        }
        Ok(region)
    }

    /// Tile `index` of `count` (numbered from 0): a strip of whole rows (see the module
    /// documentation). Every row belongs to exactly one tile.
    pub fn tile(index: u32, count: u32, width: u32, height: u32) -> Result<Region, RegionError> {
        if count == 0 || index >= count {
            return Err(RegionError::Tile {
                reason: format!("tile {index}/{count}: tiles are numbered 0 to N-1, N at least 1"),
            });
        }
        if count > height {
            return Err(RegionError::Tile {
                reason: format!(
                    "tile {index}/{count}: {count} tiles of an image {height} rows high would \
                     leave some without a row"
                ),
            });
        }
        let (base, taller) = (height / count, height % count);
        let start = |i: u32| i * base + i.min(taller);
        Region::new([0, start(index), width, start(index + 1)], width, height)
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    /// Pixels in it.
    pub fn pixels(&self) -> u64 {
        self.width() as u64 * self.height() as u64
    }

    /// Whether the two share a pixel.
    pub fn overlaps(&self, other: &Region) -> bool {
        self.x0 < other.x1 && other.x0 < self.x1 && self.y0 < other.y1 && other.y0 < self.y1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_documented_tiles() {
        let tiles: Vec<_> = (0..3).map(|i| Region::tile(i, 3, 7, 512).unwrap()).collect();
        assert_eq!(
            tiles,
            [
                Region { x0: 0, y0: 0, x1: 7, y1: 171 },
                Region { x0: 0, y0: 171, x1: 7, y1: 342 },
                Region { x0: 0, y0: 342, x1: 7, y1: 512 },
            ]
        );
    }

    /// Tiles cover every row once, in order, for counts that divide the height and counts that
    /// do not, up to one row per tile.
    #[test]
    fn tiles_cover_every_row_once() {
        for height in [1, 2, 5, 17, 100, 512] {
            for count in 1..=height.min(40) {
                let mut next = 0;
                for index in 0..count {
                    let tile = Region::tile(index, count, 3, height).unwrap();
                    assert_eq!((tile.y0, tile.x0, tile.x1), (next, 0, 3));
                    assert!(tile.height() == height / count || tile.height() == height / count + 1);
                    next = tile.y1;
                }
                assert_eq!(next, height);
            }
        }
    }

    #[test]
    fn bad_tiles_and_regions_are_errors() {
        assert!(Region::tile(4, 4, 8, 8).unwrap_err().to_string().contains("numbered 0 to N-1"));
        assert!(Region::tile(0, 0, 8, 8).is_err());
        assert!(Region::tile(0, 9, 8, 8).unwrap_err().to_string().contains("without a row"));
        assert_eq!(
            Region::new([2, 0, 2, 4], 8, 8).unwrap_err().to_string(),
            "region 2,0,2,4 is empty: it needs x0 < x1 and y0 < y1"
        );
        assert_eq!(
            Region::new([0, 0, 9, 4], 8, 8).unwrap_err().to_string(),
            "region 0,0,9,4 reaches outside the 8×8 image"
        );
    }

    #[test]
    fn overlaps() {
        let a = Region { x0: 0, y0: 0, x1: 4, y1: 4 };
        assert!(a.overlaps(&Region { x0: 3, y0: 3, x1: 5, y1: 5 }));
        assert!(!a.overlaps(&Region { x0: 4, y0: 0, x1: 5, y1: 4 }));
        assert!(!a.overlaps(&Region { x0: 0, y0: 4, x1: 4, y1: 5 }));
    }
}
