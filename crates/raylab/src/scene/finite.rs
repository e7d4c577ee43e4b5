//! Numbers in scene files that are not finite, found before anything else reads them.

use std::ops::Range;

/// The first number in a TOML text that is NaN or infinite, or too large for a 32-bit float
/// (`nan`, `inf`, `1e40`): its place, its key (like `camera.position[0]`) and its text. Checked
/// before anything else, so that every such number is reported where it is, whatever it was
/// meant to be.
pub(crate) fn first_non_finite(text: &str) -> Option<(Range<usize>, String, String)> {
    use toml::de::{DeTable, DeValue};
    fn walk(
        value: &toml::Spanned<DeValue<'_>>,
        key: &str,
    ) -> Option<(Range<usize>, String, String)> {
        match value.get_ref() {
            DeValue::Float(f) => {
                let number = f.as_str().replace('_', "").parse::<f64>().unwrap_or(f64::NAN);
                (!(number as f32).is_finite())
                    .then(|| (value.span(), key.to_string(), f.as_str().to_string()))
            }
            DeValue::Array(items) => {
                items.iter().enumerate().find_map(|(i, item)| walk(item, &format!("{key}[{i}]")))
            }
            DeValue::Table(table) => table.iter().find_map(|(name, item)| {
                let name = name.get_ref();
                walk(item, &if key.is_empty() { name.to_string() } else { format!("{key}.{name}") })
            }),
            _ => None,
        }
    }
    let table = DeTable::parse(text).ok()?;
    let root = toml::Spanned::new(table.span(), DeValue::Table(table.into_inner()));
    walk(&root, "")
}
