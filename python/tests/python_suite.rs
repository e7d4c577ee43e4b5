//! The Python package's tests (pytest, `python/tests/test_*.py`), run by `cargo test`.
//!
//! This test makes a virtual environment in the target directory (`target/python-venv`, its
//! packages from `requirements.txt`, installed again only when that file changes), builds the
//! extension module with the test's own profile (`cargo build -p raylab-python`), puts it beside
//! the package's Python files in `target/<profile>/python-package/raylab`, writes the Rust
//! library's answers for a set of rays to compare with (`rust_answers`), and runs pytest.
//!
//! Without Python 3.9 or newer, or without the package registry to install from, it says why
//! and passes; with `RAYLAB_REQUIRE_PYTHON=1` (as `.ci/run` sets it) it fails instead, and the
//! embreex comparison may not skip either (`RAYLAB_REQUIRE_EMBREEX`, passed on to pytest).

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::Vec3;
use raylab::{Accelerator, Bvh, Ray};

/// Skips with `why`, or fails when the suite is required.
fn unavailable(why: &str) {
    if std::env::var_os("RAYLAB_REQUIRE_PYTHON").is_some() {
        panic!("the Python tests are required (RAYLAB_REQUIRE_PYTHON) but {why}");
    }
    eprintln!("python_suite skipped: {why} (RAYLAB_REQUIRE_PYTHON=1 makes this a failure)");
}

/// Runs `command`, returning its output, or `None` if it could not start or failed (with its
/// output printed).
fn run(command: &mut Command) -> Option<std::process::Output> {
    let output = command.output().ok()?;
    if !output.status.success() {
        eprintln!("{command:?} failed ({})", output.status);
        eprintln!("{}", String::from_utf8_lossy(&output.stdout));
        eprintln!("{}", String::from_utf8_lossy(&output.stderr));
        return None;
    }
    Some(output)
}

/// `target/<profile>`: this test executable is `target/<profile>/deps/python_suite-…`.
fn profile_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's path");
    exe.parent().and_then(Path::parent).expect("target/<profile>/deps").to_path_buf()
}

/// The virtual environment with `requirements.txt` installed, or why there is none.
fn venv(python: &str, target: &Path, requirements: &Path) -> Result<PathBuf, String> {
    let venv = target.join("python-venv");
    let venv_python = venv.join("bin").join("python");
    let wanted = std::fs::read_to_string(requirements).expect("requirements.txt");
    let stamp = venv.join("raylab-requirements.txt");
    if venv_python.exists() && std::fs::read_to_string(&stamp).ok().as_ref() == Some(&wanted) {
        return Ok(venv_python);
    }
    let version = run(Command::new(python)
        .args(["-c", "import sys; assert sys.version_info >= (3, 9), sys.version"]));
    if version.is_none() {
        return Err(format!("`{python}` is not Python 3.9 or newer"));
    }
    if run(Command::new(python).args(["-m", "venv", "--clear"]).arg(&venv)).is_none() {
        return Err(format!("`{python} -m venv` failed (Debian: apt install python3-venv)"));
    }
    let pip = Command::new(&venv_python)
        .args(["-m", "pip", "install", "-q", "--disable-pip-version-check", "-r"])
        .arg(requirements)
        .status();
    if !matches!(pip, Ok(s) if s.success()) {
        return Err("pip could not install tests/requirements.txt (no package registry?)".into());
    }
    std::fs::write(&stamp, wanted).expect("the venv's stamp");
    Ok(venv_python)
}

/// Deterministic numbers (the library's PCG32): the same rays on every machine.
struct Numbers(raylab::sampling::Pcg32);

impl Numbers {
    fn next(&mut self) -> f32 {
        self.0.next_f32()
    }

    fn vec(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
}

/// Writes `values` as little-endian bytes.
fn write<T: Copy, const N: usize>(path: &Path, values: &[T], bytes: impl Fn(T) -> [u8; N]) {
    let data: Vec<u8> = values.iter().flat_map(|&v| bytes(v)).collect();
    std::fs::write(path, data).expect("an answers file");
}

/// The Rust library's answers on the bunny for rays of several kinds (from outside toward the
/// mesh, from inside its box, along the axes, through its vertices), for
/// `test_queries.py::test_the_rust_librarys_answers_bit_for_bit`.
fn rust_answers(mesh_path: &Path, dir: &Path) {
    std::fs::create_dir_all(dir).expect("the answers' folder");
    let mesh = raylab::load_mesh(mesh_path).expect("the bunny").flattened();
    let triangles: Vec<[Vec3; 3]> =
        mesh.triangles.iter().map(|t| t.map(|v| mesh.positions[v as usize])).collect();
    let bvh = Bvh::new(&triangles);
    let (lo, hi) = triangles
        .iter()
        .flatten()
        .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let size = hi - lo;
    let mut numbers = Numbers(raylab::sampling::Pcg32::new(27, 0));
    let mut rays = Vec::new();
    for i in 0..20_000 {
        let target = lo + numbers.vec() * size;
        let (origin, direction) = match i % 4 {
            // From a sphere around the mesh, toward a point in its box.
            0 | 1 => {
                let origin = (lo + hi) * 0.5 + (numbers.vec() - 0.5).normalize() * size.length();
                (origin, target - origin)
            }
            // From inside the box, anywhere.
            2 => (target, numbers.vec() - 0.5),
            // Through a vertex, from outside, along an axis or not.
            _ => {
                let vertex = mesh.positions[(numbers.next() * mesh.positions.len() as f32)
                    as usize
                    % mesh.positions.len()];
                let direction = if i % 8 == 3 { Vec3::Z } else { numbers.vec() - 0.5 };
                (vertex - direction * 2.0, direction)
            }
        };
        rays.push(Ray::new(origin, direction));
    }
    let origins: Vec<f32> = rays.iter().flat_map(|r| r.origin.to_array()).collect();
    let directions: Vec<f32> = rays.iter().flat_map(|r| r.direction.to_array()).collect();
    let hits: Vec<_> = rays.iter().map(|r| bvh.closest_hit(r)).collect();
    write(&dir.join("origins.f32"), &origins, f32::to_le_bytes);
    write(&dir.join("directions.f32"), &directions, f32::to_le_bytes);
    let t: Vec<f32> = hits.iter().map(|h| h.map_or(f32::INFINITY, |h| h.t)).collect();
    let triangle: Vec<i64> = hits.iter().map(|h| h.map_or(-1, |h| i64::from(h.triangle))).collect();
    let u: Vec<f32> = hits.iter().map(|h| h.map_or(0.0, |h| h.b1)).collect();
    let v: Vec<f32> = hits.iter().map(|h| h.map_or(0.0, |h| h.b2)).collect();
    write(&dir.join("t.f32"), &t, f32::to_le_bytes);
    write(&dir.join("triangle.i64"), &triangle, i64::to_le_bytes);
    write(&dir.join("u.f32"), &u, f32::to_le_bytes);
    write(&dir.join("v.f32"), &v, f32::to_le_bytes);
    // Shadow rays: each ray's segment to half its hit (never blocked) or to twice it.
    let shadow: Vec<u8> = rays
        .iter()
        .zip(&hits)
        .enumerate()
        .map(|(i, (ray, hit))| {
            let t_max = hit.map_or(1.0, |h| if i % 2 == 0 { h.t * 0.5 } else { h.t * 2.0 });
            u8::from(bvh.occluded(&Ray::segment(ray.origin, ray.direction, t_max)))
        })
        .collect();
    write(&dir.join("occluded.u8"), &shadow, |b| [b]);
}

#[test]
fn pytest_suite() {
    let package = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let python = std::env::var("RAYLAB_PYTHON").unwrap_or_else(|_| "python3".into());
    let profile = profile_dir();
    let target = profile.parent().expect("target/").to_path_buf();
    let venv_python = match venv(&python, &target, &package.join("tests/requirements.txt")) {
        Ok(p) => p,
        Err(why) => return unavailable(&why),
    };

    // The extension module, built with this test's profile.
    let mut build = Command::new(env!("CARGO"));
    build.args(["build", "-q", "-p", "raylab-python"]).current_dir(&package);
    if !cfg!(debug_assertions) {
        build.arg("--release");
    }
    run(&mut build).expect("cargo build -p raylab-python");
    // The command, to compare `raylab.render` with `raylab render`.
    let mut build = Command::new(env!("CARGO"));
    build.args(["build", "-q", "-p", "raylab-cli"]).current_dir(&package);
    if !cfg!(debug_assertions) {
        build.arg("--release");
    }
    run(&mut build).expect("cargo build -p raylab-cli");
    let staged = profile.join("python-package").join("raylab");
    std::fs::create_dir_all(&staged).expect("the staged package");
    for entry in std::fs::read_dir(package.join("raylab")).expect("python/raylab") {
        let path = entry.expect("a package file").path();
        if path.extension().is_some_and(|e| e == "py") {
            std::fs::copy(&path, staged.join(path.file_name().expect("a name"))).expect("copy");
        }
    }
    std::fs::copy(profile.join("lib_raylab.so"), staged.join("_raylab.abi3.so"))
        .expect("the extension module");

    let meshes = package.join("../crates/raylab/tests/data/meshes");
    let answers = profile.join("python-answers");
    rust_answers(&meshes.join("bunny.obj.gz"), &answers);

    let status = Command::new(&venv_python)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider", "-r", "s"])
        .arg(package.join("tests"))
        // Not the package's folder: `python -m` puts the working folder first on the path,
        // where `python/raylab` has no extension module.
        .current_dir(&profile)
        .env("PYTHONPATH", staged.parent().expect("python-package"))
        .env("RAYLAB_RUST_ANSWERS", &answers)
        .env("RAYLAB_TEST_MESHES", &meshes)
        .env("RAYLAB_BIN", profile.join("raylab"))
        .env("RAYLAB_REPOSITORY", package.parent().expect("the repository"))
        .status()
        .expect("pytest runs");
    assert!(status.success(), "pytest failed ({status}): see its report above");
}
