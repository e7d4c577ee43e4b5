//! What the OBJ line reader and the material library loader share, which tobj holds apart
//! ([`Shared`]): the line the reader is on, the first error, and the libraries' materials,
//! textures and warnings.

use std::cell::{Cell, RefCell};
use std::path::{Path, PathBuf};

use crate::mesh::MeshMaterial;
use crate::scene::mesh_file::{LoadError, Location, quoted};
use crate::scene::mtl::{TextureFiles, parse_mtl};

/// Finds and reads the material library that an `mtllib` line names: its path and content.
pub(crate) type ReadLibrary<'a> = dyn Fn(&str) -> Result<(PathBuf, Vec<u8>), LoadError> + 'a;

/// State shared by the line reader and the material library loader, which tobj holds apart.
pub(super) struct Shared<'a> {
    /// The OBJ file, for messages.
    pub(super) obj_path: &'a Path,
    pub(super) read_library: &'a ReadLibrary<'a>,
    /// The line the reader is on.
    pub(super) line: Cell<u64>,
    /// The first error found by us rather than by tobj; the reader stops tobj once it is set.
    pub(super) failure: RefCell<Option<LoadError>>,
    /// Every library's materials, in the order tobj numbers them.
    pub(super) materials: RefCell<Vec<MeshMaterial>>,
    pub(super) warnings: RefCell<Vec<String>>,
    /// The texture files read so far.
    pub(super) textures: RefCell<TextureFiles>,
    /// Whether some library could not be read (then unknown material names are expected).
    pub(super) library_missing: Cell<bool>,
}

impl Shared<'_> {
    /// tobj's material loader: reads the libraries that an `mtllib` line names.
    pub(super) fn load_library(&self, requested: &Path) -> tobj::MTLLoadResult {
        let mut result: tobj::MTLLoadResult = Ok((Vec::new(), Default::default()));
        let requested = requested.to_string_lossy();
        let line = self.line.get();
        let ignored = |error: LoadError| {
            self.library_missing.set(true);
            self.warnings.borrow_mut().push(format!(
                "line {line}: material library ignored, the surfaces get the default grey: {error}"
            ));
        };
        // A name may contain spaces; if no file has the whole name, it is a list of names.
        match self.read_one(&requested) {
            Ok(library) => self.add_library(library, &mut result),
            Err(error) if requested.split_whitespace().nth(1).is_none() => ignored(error),
            Err(_) => {
                for name in requested.split_whitespace() {
                    match self.read_one(name) {
                        Ok(library) => self.add_library(library, &mut result),
                        Err(error) => ignored(error),
                    }
                }
            }
        }
        result
    }

    /// Reads one library, trying `\` as a folder separator if the name as written is not found.
    fn read_one(&self, name: &str) -> Result<(PathBuf, Vec<u8>), LoadError> {
        if name.is_empty() {
            return Err(LoadError::Invalid {
                path: self.obj_path.into(),
                message: "`mtllib` names no file".into(),
            });
        }
        match (self.read_library)(name) {
            Err(error) if name.contains('\\') => {
                (self.read_library)(&name.replace('\\', "/")).map_err(|_| error)
            }
            found => found,
        }
    }

    fn add_library(&self, (path, bytes): (PathBuf, Vec<u8>), result: &mut tobj::MTLLoadResult) {
        match parse_mtl(&bytes) {
            Ok((library, ignored)) => {
                for (line, message) in ignored {
                    self.warnings
                        .borrow_mut()
                        .push(format!("{}:{line}: ignored: {message}", path.display()));
                }
                let mut materials = Vec::with_capacity(library.len());
                for (mut material, texture) in library {
                    if let Some(line) = texture {
                        match self.textures.borrow_mut().load(&path, &line) {
                            Ok(texture) => material.textures.base_color = Some(texture),
                            Err(error) => self.warnings.borrow_mut().push(format!(
                                "{}:{}: the texture of material {} is ignored: {error}",
                                path.display(),
                                line.line,
                                quoted(&material.name)
                            )),
                        }
                    }
                    materials.push(material);
                }
                if let Ok((list, names)) = result {
                    for material in &materials {
                        names.insert(material.name.clone(), list.len());
                        list.push(tobj::Material {
                            name: material.name.clone(),
                            ..Default::default()
                        });
                    }
                }
                self.materials.borrow_mut().extend(materials);
            }
            Err((line, message)) => {
                let error = LoadError::Syntax { path, location: Location::Line(line), message };
                self.failure.borrow_mut().get_or_insert(error);
            }
        }
    }
}
