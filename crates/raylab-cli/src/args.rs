//! Parsers for command-line values: every number must be finite, every size sensible.

use glam::Vec3;

/// Parses a finite number; `NaN`, `inf` and values beyond `f32` (like `1e39`) are refused.
pub fn finite_f32(text: &str) -> Result<f32, String> {
    let value: f32 = text.trim().parse().map_err(|_| format!("'{text}' is not a number"))?;
    if value.is_finite() { Ok(value) } else { Err(format!("'{text}' is not a finite number")) }
}

/// Parses a finite number greater than zero.
pub fn positive_f32(text: &str) -> Result<f32, String> {
    let value = finite_f32(text)?;
    if value > 0.0 { Ok(value) } else { Err(format!("{text} must be greater than 0")) }
}

/// Parses a time in seconds, greater than zero and at most a century (a larger one would not fit
/// a `Duration` and means "no limit" anyway).
pub fn seconds(text: &str) -> Result<std::time::Duration, String> {
    const CENTURY: f32 = 100.0 * 365.25 * 86400.0;
    let value = positive_f32(text)?;
    if value > CENTURY {
        return Err(format!("{text} seconds is more than a century"));
    }
    std::time::Duration::try_from_secs_f32(value).map_err(|e| format!("{text}: {e}"))
}

/// Parses a finite number that is zero or more.
pub fn non_negative_f32(text: &str) -> Result<f32, String> {
    let value = finite_f32(text)?;
    if value >= 0.0 { Ok(value) } else { Err(format!("{text} must not be negative")) }
}

/// Parses a field of view in degrees, strictly between 0 and 180.
pub fn fov_deg(text: &str) -> Result<f32, String> {
    let value = finite_f32(text)?;
    if value > 0.0 && value < 180.0 {
        Ok(value)
    } else {
        Err(format!("a field of view must be between 0° and 180° (exclusive), not {text}"))
    }
}

/// Parses a pitch in degrees, from -89 to 89 (beyond, the view would flip over the vertical).
pub fn pitch_deg(text: &str) -> Result<f32, String> {
    let value = finite_f32(text)?;
    if (-89.0..=89.0).contains(&value) {
        Ok(value)
    } else {
        Err(format!("a pitch must be between -89° and 89°, not {text}"))
    }
}

/// Parses `X,Y,Z` into a vector of finite numbers.
pub fn vec3(text: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = text.split(',').collect();
    let [x, y, z] = parts[..] else {
        return Err(format!("expected three numbers X,Y,Z (like 0,-0.5,-0.7), not '{text}'"));
    };
    Ok(Vec3::new(finite_f32(x)?, finite_f32(y)?, finite_f32(z)?))
}

/// An image size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    /// Width in pixels, at least 1.
    pub width: u32,
    /// Height in pixels, at least 1.
    pub height: u32,
}

/// Parses `WIDTHxHEIGHT` (or `W×H`), both at least 1.
pub fn size(text: &str) -> Result<Size, String> {
    let Some((w, h)) = text.split_once(['x', 'X', '×']) else {
        return Err(format!("expected WIDTHxHEIGHT (like 500x500), not '{text}'"));
    };
    let dimension = |name: &str, value: &str| -> Result<u32, String> {
        let value = value.trim();
        match value.parse::<i128>() {
            Ok(n) if n < 1 => Err(format!("{name} must be at least 1 pixel, not {value}")),
            Ok(n) => u32::try_from(n).map_err(|_| {
                format!("{name} {value} is larger than the largest image ({})", u32::MAX)
            }),
            Err(_) => Err(format!("{name} '{value}' is not a whole number")),
        }
    };
    Ok(Size { width: dimension("width", w)?, height: dimension("height", h)? })
}

/// Parses `I/N`: tile `I` of `N`, numbered from 0.
pub fn tile(text: &str) -> Result<(u32, u32), String> {
    let number = |value: &str| value.trim().parse::<u32>().ok();
    match text.split_once('/').map(|(i, n)| (number(i), number(n))) {
        Some((Some(i), Some(n))) if n >= 1 && i < n => Ok((i, n)),
        Some((Some(i), Some(n))) => {
            Err(format!("tile {i}/{n}: tiles are numbered 0 to N-1, N at least 1"))
        }
        _ => Err(format!("expected I/N, tile I of N numbered from 0 (like 0/4), not '{text}'")),
    }
}

/// Parses `X0,Y0,X1,Y1`: four whole numbers, pixel corners (checked against the image later).
pub fn region(text: &str) -> Result<[u32; 4], String> {
    let numbers: Vec<Option<u32>> = text.split(',').map(|v| v.trim().parse().ok()).collect();
    match numbers[..] {
        [Some(x0), Some(y0), Some(x1), Some(y1)] => Ok([x0, y0, x1, y1]),
        _ => Err(format!(
            "expected X0,Y0,X1,Y1, four whole numbers (columns X0..X1 and rows Y0..Y1, the ends \
             excluded, like 0,0,256,128), not '{text}'"
        )),
    }
}

/// Parses `A..B` (frames A to B, both included, A ≤ B) or `N` (one frame).
pub fn frames(text: &str) -> Result<(u32, u32), String> {
    let number = |value: &str| value.trim().parse::<u32>().ok();
    let range = match text.split_once("..") {
        Some((a, b)) => (number(a), number(b.strip_prefix('=').unwrap_or(b))),
        None => (number(text), number(text)),
    };
    match range {
        (Some(a), Some(b)) if a <= b => Ok((a, b)),
        (Some(a), Some(b)) => {
            Err(format!("frames {a}..{b}: the first must not come after the last"))
        }
        _ => Err(format!(
            "expected A..B, frames A to B both included (like 1..48), or one frame N, not '{text}'"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_must_be_finite() {
        assert_eq!(finite_f32("-2.5"), Ok(-2.5));
        for bad in ["nan", "NaN", "inf", "-inf", "1e39", "abc", ""] {
            assert!(finite_f32(bad).is_err(), "{bad}");
        }
        assert!(positive_f32("0").is_err());
        assert!(non_negative_f32("-1").is_err() && non_negative_f32("0") == Ok(0.0));
        assert!(fov_deg("180").is_err() && fov_deg("0").is_err() && fov_deg("90").is_ok());
        assert!(pitch_deg("90").is_err() && pitch_deg("-89") == Ok(-89.0));
    }

    #[test]
    fn vectors_need_three_finite_numbers() {
        assert_eq!(vec3("0,-0.5,-0.7"), Ok(Vec3::new(0.0, -0.5, -0.7)));
        assert!(vec3("1,2").is_err());
        assert!(vec3("1,2,3,4").is_err());
        assert!(vec3("1,nan,3").unwrap_err().contains("'nan'"));
    }

    #[test]
    fn frames_and_their_file_names() {
        assert_eq!(frames("1..48"), Ok((1, 48)));
        assert_eq!(frames("3..=5"), Ok((3, 5)));
        assert_eq!(frames("7"), Ok((7, 7)));
        assert!(frames("5..3").unwrap_err().contains("must not come after"));
        assert!(frames("a..3").is_err() && frames("").is_err() && frames("-1..2").is_err());
    }

    #[test]
    fn tiles_and_regions() {
        assert_eq!(tile("0/4"), Ok((0, 4)));
        assert_eq!(tile("3/4"), Ok((3, 4)));
        assert!(tile("4/4").unwrap_err().contains("numbered 0 to N-1"));
        assert!(tile("0/0").is_err() && tile("1").is_err() && tile("-1/4").is_err());
        assert_eq!(region("0,8,16,24"), Ok([0, 8, 16, 24]));
        assert!(region("0,8,16").unwrap_err().contains("X0,Y0,X1,Y1"));
        assert!(region("0,8,16,-1").is_err());
    }

    #[test]
    fn sizes_are_positive_whole_numbers() {
        assert_eq!(size("640x480"), Ok(Size { width: 640, height: 480 }));
        assert_eq!(size("2×3"), Ok(Size { width: 2, height: 3 }));
        assert!(size("0x10").unwrap_err().contains("at least 1"));
        assert!(size("-5x10").unwrap_err().contains("at least 1"));
        assert!(size("10x2.5").unwrap_err().contains("whole number"));
        assert!(size("99999999999x1").unwrap_err().contains("larger"));
        assert!(size("500").is_err());
    }
}
