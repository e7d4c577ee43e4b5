//! The repository stands alone: no committed file names a path of the machine it was made on.
//!
//! A user's clone has none of the build machine's folders, so an absolute path into one (a
//! home folder, the build machine's work folder) in a doc, a script or a recorded file is
//! either wrong for every reader or leaks where it was made. Paths relative to the checkout
//! (`../shared/data/…`, the data collection beside it) and system paths (`/usr/lib/…`) are fine.

use std::path::{Path, PathBuf};

/// Absolute path prefixes of a build machine: home folders and the work folder. Written in
/// pieces so that this file does not match itself.
fn machine_prefixes() -> Vec<String> {
    ["work", "root", "home", "Users"].iter().map(|folder| format!("/{folder}/")).collect()
}

/// Where a text holds a machine path: (line, the line), for every prefix found not as part of
/// a longer path or word (a home folder counts; the same letters inside `src/…` or a URL do not).
fn machine_paths(text: &str, prefixes: &[String]) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let hit = prefixes.iter().any(|prefix| {
            line.match_indices(prefix.as_str()).any(|(at, _)| {
                let before = line[..at].chars().next_back();
                !before.is_some_and(|c| {
                    c.is_alphanumeric() || matches!(c, '.' | '_' | '-' | '/' | '~')
                })
            })
        });
        if hit {
            found.push((number + 1, line.trim().chars().take(160).collect()));
        }
    }
    found
}

/// Every file of the repository: `git ls-files` where git knows the checkout, else a walk that
/// leaves out build output and git's own folder.
fn repository_files(root: &Path) -> Vec<PathBuf> {
    let listed = std::process::Command::new("git")
        .args(["ls-files", "-z"])
        .current_dir(root)
        .output()
        .ok()
        .filter(|out| out.status.success() && !out.stdout.is_empty());
    if let Some(out) = listed {
        return out
            .stdout
            .split(|&b| b == 0)
            .filter(|name| !name.is_empty())
            .map(|name| root.join(String::from_utf8_lossy(name).as_ref()))
            .collect();
    }
    let mut files = Vec::new();
    let mut folders = vec![root.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in
            std::fs::read_dir(&folder).unwrap_or_else(|e| panic!("{}: {e}", folder.display()))
        {
            let path = entry.expect("a directory entry").path();
            let name = path.file_name().unwrap_or_default().to_string_lossy().into_owned();
            if path.is_dir() {
                if name != "target" && name != ".git" {
                    folders.push(path);
                }
            } else {
                files.push(path);
            }
        }
    }
    files
}

#[test]
fn no_committed_file_names_a_build_machine_path() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let prefixes = machine_prefixes();
    let files = repository_files(&root);
    assert!(files.iter().any(|f| f.ends_with("README.md")), "the reader found no README");
    let mut offenders = Vec::new();
    for file in files {
        // Binary files (images, compressed data) and files git lists but the checkout lacks.
        let Ok(text) = std::fs::read_to_string(&file) else { continue };
        for (line, content) in machine_paths(&text, &prefixes) {
            let shown = file.strip_prefix(&root).unwrap_or(&file).display().to_string();
            offenders.push(format!("{shown}:{line}: {content}"));
        }
    }
    assert!(
        offenders.is_empty(),
        "build-machine paths in committed files:\n{}",
        offenders.join("\n")
    );
}

#[test]
fn machine_paths_are_found_and_relative_ones_are_not() {
    let prefixes = machine_prefixes();
    let home = format!("see {}me/data.obj", prefixes[2]);
    let text = format!(
        "fine: ../shared/data/teapot.obj\nfine: /usr/lib/x86_64-linux-gnu/libLLVM-19.so\n{home}\n\
         fine: https://example.org{}x\nfine: src{}x.rs\n`{}x/y`",
        prefixes[0], prefixes[2], prefixes[0]
    );
    let found: Vec<usize> =
        machine_paths(&text, &prefixes).into_iter().map(|(line, _)| line).collect();
    assert_eq!(found, vec![3, 6]);
}
