//! One loader for every command that takes a scene: a JSON scene file, or a binary complex
//! file (`vcx build SCENE.json -o FILE.vcx`, `docs/format.md`), told apart by the magic
//! bytes `VCX\0` (or the extension `.vcx`).
//!
//! A `.vcx` file is decoded and fully validated ([`vcx::format::decode`]); its scene has no
//! names or extra fields (the format stores geometry only) and its complex is used where a
//! command needs the complex of the whole scene, its history (if stored, `vcx build
//! --history`) where a command needs point location (`vcx locate`). Commands that need
//! another complex (views leave screens out), or a history the file does not store,
//! rebuild it from the file's scene.
//!
//! A corrupt file is one `error:` line naming the file, the part, element and field and the
//! byte offset at fault, with exit status 2.

use std::path::Path;

use vcx::format::{FormatError, Header};
use vcx::partition::{build_by_sweep, Complex, ComplexError, History};
use vcx::SceneRef;
use vcx_demo::scene_file::{self, ObjectMeta, SceneFile, SceneFileError};

use crate::cmd::build::Built;
use crate::cmd::Failure;

/// What a `.vcx` file holds besides the scene.
#[derive(Debug)]
pub struct Stored {
    /// The header.
    pub header: Header,
    /// The complex of the whole scene, validated.
    pub complex: Complex,
    /// The construction history, if the file stores one (validated; its live cylinders
    /// are `complex`'s).
    pub history: Option<History>,
    /// The file's length in bytes.
    pub bytes: usize,
}

/// A loaded scene, and the stored complex if it came from a `.vcx` file.
#[derive(Debug)]
pub struct Input {
    /// The scene (from a `.vcx` file: no names, no extra fields).
    pub file: SceneFile,
    /// The header and complex of a `.vcx` file.
    pub stored: Option<Stored>,
}

/// Whether these bytes (of the file at `path`) are to be read as a binary complex file.
pub fn is_vcx(path: &Path, bytes: &[u8]) -> bool {
    bytes.starts_with(&vcx::format::MAGIC) || path.extension().is_some_and(|e| e == "vcx")
}

/// Reads and decodes a binary complex file; errors are `FormatError`s (for tools that
/// print their own messages).
pub fn decode_file(bytes: &[u8]) -> Result<vcx::format::Loaded, FormatError> {
    vcx::format::decode(bytes)
}

/// Loads a JSON scene or a `.vcx` file; the failure names the file.
pub fn load(path: &Path) -> Result<Input, Failure> {
    let bytes = std::fs::read(path).map_err(|source| {
        Failure::bad_input(
            SceneFileError::Io {
                path: path.to_path_buf(),
                source,
            }
            .to_string(),
        )
    })?;
    from_bytes(path, &bytes)
}

/// As [`load`], from the file's bytes (`path` names it in errors and tells the format by
/// its extension).
pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Input, Failure> {
    if !is_vcx(path, bytes) {
        let file = scene_file::parse_bytes(bytes)
            .map_err(|e| Failure::bad_input(format!("{}: {e}", path.display())))?;
        return Ok(Input { file, stored: None });
    }
    let loaded = decode_file(bytes).map_err(|e| vcx_error(path, &e))?;
    let n = loaded.scene.as_ref().len();
    Ok(Input {
        file: SceneFile {
            scene: loaded.scene,
            meta: vec![ObjectMeta::default(); n],
            top: serde_json::Map::new(),
        },
        stored: Some(Stored {
            header: loaded.header,
            complex: loaded.complex,
            history: loaded.history,
            bytes: bytes.len(),
        }),
    })
}

/// The one-line failure for a corrupt `.vcx` file (exit status 2).
pub fn vcx_error(path: &Path, e: &FormatError) -> Failure {
    Failure::bad_input(format!(
        "{}: not a valid vcx complex file: {e}",
        path.display()
    ))
}

impl Input {
    /// The stored complex if `scene` is the whole loaded scene (same objects, same
    /// vertices), else `None`.
    fn stored_for(&self, scene: &SceneRef<'_>) -> Option<&Complex> {
        let whole = self.file.scene.as_ref();
        let same = scene.objects() == whole.objects() && scene.vertices() == whole.vertices();
        self.stored.as_ref().filter(|_| same).map(|s| &s.complex)
    }

    /// The stored history if `scene` is the whole loaded scene and the file has one.
    pub fn history_for(&self, scene: &SceneRef<'_>) -> Option<&History> {
        self.stored_for(scene)?;
        self.stored.as_ref()?.history.as_ref()
    }

    /// The complex of `scene` (the loaded scene or a `SubScene` of it) for many walks: the
    /// stored one when it is the whole scene, else built by the rotational sweep, with its
    /// arc-vertex index ([`Complex::with_arc_vertices`]: it pays for itself after some
    /// thousands of views, so one-shot commands go without it).
    pub fn complex_for(&self, scene: &SceneRef<'_>) -> Result<Complex, ComplexError> {
        let complex = match self.stored_for(scene) {
            Some(c) => c.clone(),
            None => build_by_sweep(scene)?,
        };
        Ok(complex.with_arc_vertices(scene))
    }

    /// As [`Input::complex_for`], as a [`Built`] for the commands of `vcx build`'s
    /// family (failures of a construction are internal, exit status 3).
    pub fn built(&self, path: &Path, scene: &SceneRef<'_>) -> Result<Built, Failure> {
        match self.stored_for(scene) {
            Some(c) => Ok(Built {
                complex: c.clone(),
                whole: None,
                history: None,
                seconds: 0.0,
            }),
            None => crate::cmd::build::build_checked(path, scene),
        }
    }
}
