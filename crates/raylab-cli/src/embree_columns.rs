//! Embree's figures beside raylab's: `raylab bench --embree summary.json`.
//!
//! The Embree reference program (see `docs/benchmarking.md`) writes a `summary.json` with its
//! throughput per ray set, query, API mode and thread count. Given one or two of them (Embree's
//! default run and its watertight `--robust` run, both made with `--rays DIR` on the ray files
//! raylab traces), `raylab bench` prints each Embree figure beside its own with the ratio, so the
//! side-by-side comparison of the protocol needs no hand-copying. A summary of another mesh is
//! refused; one whose ray counts differ from the traced sets is compared with a warning.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::Deserialize;

/// The part of Embree's `summary.json` that is compared.
#[derive(Debug, Deserialize)]
struct Summary {
    embree: EmbreeInfo,
    mesh_stats: MeshStats,
    results: Vec<Row>,
}

#[derive(Debug, Deserialize)]
struct EmbreeInfo {
    version: String,
    robust: bool,
}

#[derive(Debug, Deserialize)]
struct MeshStats {
    triangles: usize,
}

/// One measurement: `mode` is `single` (`rtcIntersect1`/`rtcOccluded1`), `packet16` and so on.
#[derive(Debug, Deserialize)]
struct Row {
    set: String,
    query: String,
    mode: String,
    threads: usize,
    rays: usize,
    mrays_per_s: f64,
}

/// One Embree run's figures, labelled.
#[derive(Debug)]
pub struct Reference {
    label: String,
    path: PathBuf,
    rows: Vec<Row>,
}

/// What raylab measured for one line of the table: set, query (`closest`, `occluded` or
/// `packet`), rays, and Mrays/s per thread count.
pub struct Measured<'a> {
    pub set: &'a str,
    pub query: &'a str,
    pub rays: usize,
    pub mrays_per_s: &'a [(usize, f64)],
}

/// Reads an Embree `summary.json`, refusing one made for a mesh of another triangle count.
pub fn load(path: &Path, triangles: usize) -> Result<Reference> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read Embree summary '{}'", path.display()))?;
    let summary: Summary = serde_json::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "'{}' line {} column {}: not an Embree summary.json: {e}",
            path.display(),
            e.line(),
            e.column()
        )
    })?;
    if summary.mesh_stats.triangles != triangles {
        bail!(
            "'{}' is Embree's run on {} triangles, not this mesh's {triangles}",
            path.display(),
            summary.mesh_stats.triangles
        );
    }
    let mode = if summary.embree.robust { " robust" } else { "" };
    Ok(Reference {
        label: format!("Embree {}{mode}", summary.embree.version),
        path: path.to_path_buf(),
        rows: summary.results,
    })
}

impl Reference {
    /// Embree's figure for raylab's line: single rays for `closest`/`occluded`, 16-wide packets
    /// for raylab's packets, on the same set, query and thread count.
    fn figure(&self, measured: &Measured, threads: usize) -> Option<&Row> {
        let (query, mode) = match measured.query {
            "packet" => ("closest", "packet16"),
            query => (query, "single"),
        };
        self.rows.iter().find(|r| {
            r.set == measured.set && r.query == query && r.mode == mode && r.threads == threads
        })
    }
}

/// The table of raylab's figures beside each reference's, with ratios raylab / Embree.
pub fn table(references: &[Reference], measured: &[Measured]) -> String {
    let mut out = String::from("beside Embree (Mrays/s, and raylab / Embree):\n");
    out += &format!("{:<9} {:<9} {:>7} {:>9}", "set", "query", "threads", "raylab");
    for reference in references {
        out += &format!(" {:>26}", reference.label);
    }
    out += "\n";
    let mut different_rays = Vec::new();
    for line in measured {
        for &(threads, ours) in line.mrays_per_s {
            out += &format!("{:<9} {:<9} {threads:>7} {ours:>9.2}", line.set, line.query);
            for reference in references {
                match reference.figure(line, threads) {
                    Some(row) => {
                        if row.rays != line.rays {
                            different_rays.push(format!(
                                "{} traced {} {} rays, raylab {}",
                                reference.path.display(),
                                row.rays,
                                line.set,
                                line.rays
                            ));
                        }
                        let ratio = format!("({:.2}×)", ours / row.mrays_per_s);
                        out += &format!(" {:>17.2} {ratio:>8}", row.mrays_per_s);
                    }
                    None => out += &format!(" {:>26}", "—"),
                }
            }
            out += "\n";
        }
    }
    different_rays.sort();
    different_rays.dedup();
    for warning in different_rays {
        out += &format!("warning: not the same rays: {warning}\n");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(robust: bool, triangles: usize) -> String {
        format!(
            r#"{{"tool": "embree_bench", "embree": {{"version": "3.13.5", "robust": {robust}}},
            "mesh_stats": {{"triangles": {triangles}}},
            "results": [
              {{"set": "primary", "query": "closest", "mode": "single", "threads": 1,
                "rays": 100, "mrays_per_s": 10.0}},
              {{"set": "primary", "query": "closest", "mode": "packet16", "threads": 1,
                "rays": 100, "mrays_per_s": 40.0}},
              {{"set": "shadow", "query": "occluded", "mode": "single", "threads": 1,
                "rays": 90, "mrays_per_s": 20.0}}
            ]}}"#
        )
    }

    #[test]
    fn figures_sit_beside_raylabs_with_ratios() {
        let dir = tempfile::tempdir().unwrap();
        let default = dir.path().join("default.json");
        let robust = dir.path().join("robust.json");
        std::fs::write(&default, summary(false, 32)).unwrap();
        std::fs::write(&robust, summary(true, 32)).unwrap();
        let references = [load(&default, 32).unwrap(), load(&robust, 32).unwrap()];
        let measured = [
            Measured { set: "primary", query: "closest", rays: 100, mrays_per_s: &[(1, 15.0)] },
            Measured { set: "shadow", query: "occluded", rays: 80, mrays_per_s: &[(1, 30.0)] },
            Measured { set: "diffuse", query: "closest", rays: 100, mrays_per_s: &[(1, 5.0)] },
            Measured { set: "primary", query: "packet", rays: 100, mrays_per_s: &[(1, 20.0)] },
        ];
        let table = table(&references, &measured);
        let lines: Vec<&str> = table.lines().collect();
        assert!(lines[1].contains("Embree 3.13.5") && lines[1].contains("Embree 3.13.5 robust"));
        let cells = |i: usize| lines[i].split_whitespace().collect::<Vec<_>>();
        assert_eq!(
            cells(2),
            ["primary", "closest", "1", "15.00", "10.00", "(1.50×)", "10.00", "(1.50×)"]
        );
        assert_eq!(
            cells(3),
            ["shadow", "occluded", "1", "30.00", "20.00", "(1.50×)", "20.00", "(1.50×)"]
        );
        // No Embree figure for a set it did not trace; packets against its 16-wide packets.
        assert_eq!(cells(4), ["diffuse", "closest", "1", "5.00", "—", "—"]);
        assert_eq!(
            cells(5),
            ["primary", "packet", "1", "20.00", "40.00", "(0.50×)", "40.00", "(0.50×)"]
        );
        // 90 shadow rays against raylab's 80: said once per file.
        assert_eq!(table.matches("warning: not the same rays").count(), 2, "{table}");
    }

    #[test]
    fn other_meshes_and_malformed_files_are_one_line_errors() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("summary.json");
        std::fs::write(&path, summary(false, 32)).unwrap();
        let error = load(&path, 33).unwrap_err().to_string();
        assert!(error.contains("32 triangles, not this mesh's 33"), "{error}");
        std::fs::write(&path, "{\"embree\": {\"version\": 3}}").unwrap();
        let error = format!("{:#}", load(&path, 32).unwrap_err());
        assert!(error.contains("summary.json' line 1 column") && !error.contains('\n'), "{error}");
        let error = format!("{:#}", load(&dir.path().join("none.json"), 32).unwrap_err());
        assert!(error.contains("none.json"), "{error}");
    }
}
