//! README's headline figures come from BENCHMARKS.md: every figure in README's "Headline
//! numbers" section (a number with a decimal point, or a range such as `0.78–0.90`) must appear,
//! written the same way, in BENCHMARKS.md, where its command, machine and date are; and the
//! figures of each row of README's table must all be in one section of BENCHMARKS.md (one
//! benchmark), not gathered from several. So README cannot quote a figure that was never
//! measured, or one BENCHMARKS.md has since replaced.
//!
//! Version numbers (`3.13.5`) are not figures; whole numbers (sizes, sample counts, years) are
//! left out, as they name settings more often than results.

use std::path::Path;

/// The heading of the README section whose figures are checked.
const HEADLINE: &str = "## Headline numbers";

#[test]
fn every_headline_figure_of_the_readme_is_in_benchmarks() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let read = |name: &str| {
        std::fs::read_to_string(root.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    let (readme, benchmarks) = (read("README.md"), read("BENCHMARKS.md"));
    let section = section(&readme, HEADLINE)
        .unwrap_or_else(|| panic!("README.md has no section '{HEADLINE}'"));
    // The check must see the table: an empty list would pass whatever README says.
    let figures = figures(section);
    assert!(
        figures.len() >= 8,
        "only {} figures found in README's headline: {figures:?}",
        figures.len()
    );
    let missing = missing_figures(section, &benchmarks);
    assert!(
        missing.is_empty(),
        "README.md quotes figures that BENCHMARKS.md does not have (measure them there, with \
         their command, machine and date, or quote the ones it has): {missing:?}"
    );
    let scattered = rows_without_a_section(section, &benchmarks);
    assert!(
        scattered.is_empty(),
        "rows of README.md's headline table whose figures no one section of BENCHMARKS.md \
         has together: {scattered:#?}"
    );
}

/// The rows of `readme`'s tables (lines starting with `|`) whose figures no one `## ` section
/// of `benchmarks` holds all of.
fn rows_without_a_section(readme: &str, benchmarks: &str) -> Vec<String> {
    let sections: Vec<Vec<String>> = benchmarks.split("\n## ").map(figures).collect();
    readme
        .lines()
        .filter(|line| line.starts_with('|'))
        .filter(|row| {
            let wanted = figures(row);
            !wanted.is_empty()
                && !sections.iter().any(|known| wanted.iter().all(|f| known.contains(f)))
        })
        .map(str::to_owned)
        .collect()
}

/// The text of the section that starts at the line `heading`, up to the next `## ` heading.
fn section<'a>(text: &'a str, heading: &str) -> Option<&'a str> {
    let start = text.find(&format!("\n{heading}\n"))? + 1;
    let body = &text[start + heading.len()..];
    let end = body.find("\n## ").map_or(body.len(), |i| i + 1);
    Some(&body[..end])
}

/// The figures of `text`: numbers with a decimal point (`4.07`, `0.00915`) and ranges
/// (`4.6–4.7`, `31–32`), in order; not version numbers (`3.13.5`) or whole numbers.
fn figures(text: &str) -> Vec<String> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let starts = chars[i].is_ascii_digit() && (i == 0 || !is_number_char(chars[i - 1]));
        if !starts {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < chars.len() && is_number_char(chars[j]) {
            j += 1;
        }
        // A trailing point or dash ends a sentence or a phrase, not the number.
        while j > i && matches!(chars[j - 1], '.' | '–') {
            j -= 1;
        }
        let token: String = chars[i..j].iter().collect();
        let version = token.split('–').any(|part| part.matches('.').count() > 1);
        if (token.contains('.') || token.contains('–')) && !version {
            out.push(token);
        }
        i = j.max(i + 1);
    }
    out
}

fn is_number_char(c: char) -> bool {
    c.is_ascii_digit() || c == '.' || c == '–'
}

/// The figures of `readme` that `benchmarks` does not have as a figure of its own.
fn missing_figures(readme: &str, benchmarks: &str) -> Vec<String> {
    let known = figures(benchmarks);
    let mut missing: Vec<String> =
        figures(readme).into_iter().filter(|figure| !known.contains(figure)).collect();
    missing.dedup();
    missing
}

mod tests {
    use super::*;

    #[test]
    fn figures_are_numbers_with_a_point_and_ranges() {
        let text = "4.07 s; 0.78–0.90× Embree 3.13.5 at 512², 64 spp, 31–32 bytes (2026-11-26). \
                    It took 4.3 ms.";
        assert_eq!(figures(text), ["4.07", "0.78–0.90", "31–32", "4.3"]);
    }

    #[test]
    fn a_figure_benchmarks_does_not_have_is_reported() {
        let benchmarks = "| bunny | 8.17 | 0.78–0.90× | 4.07 s |\nmedian 14.3 ms";
        let readme = "raylab takes 4.07 s, 0.78–0.90× Embree, 9.99× Mitsuba, and 4.3 ms.";
        // 9.99 is nowhere; 4.3 only inside 14.3, which is another figure.
        assert_eq!(missing_figures(readme, benchmarks), ["9.99", "4.3"]);
        assert!(missing_figures("4.07 s and 0.78–0.90×", benchmarks).is_empty());
    }

    #[test]
    fn a_row_whose_figures_come_from_two_benchmarks_is_reported() {
        let benchmarks = "# B\n## Rays\n| bunny | 8.17 |\n## Renders\n| box | 4.07 s |\n";
        let readme = "| rays | 8.17 |\n| both | 8.17 and 4.07 |\n| box | 4.07 s |\n| none | 5 |";
        assert_eq!(rows_without_a_section(readme, benchmarks), ["| both | 8.17 and 4.07 |"]);
    }

    #[test]
    fn the_section_ends_at_the_next_heading() {
        let text = "# t\n## Headline numbers\n| a | 1.5× |\n## Next\n2.5×\n";
        assert_eq!(section(text, HEADLINE), Some("\n| a | 1.5× |\n"));
        assert_eq!(section("no such heading", HEADLINE), None);
    }
}
