//! `vcx inspect FILE.vcx [--json]`: the header of a binary complex file and the size of
//! each part in bytes (layout: `docs/format.md`).
//!
//! The whole file is decoded and validated first, as every command that loads it would: a
//! corrupt file is one `error:` line naming the byte offset, part, element and field at
//! fault, exit status 2.
//!
//! Text output, one line per part:
//!
//! ```text
//! FILE: vcx complex format version 3, 1,879 bytes, seed 0, history compacted: yes
//!   header          56 bytes
//!   scene          595 bytes  16 objects, 81 vertices
//!   complex      1,224 bytes  514 vertices (257 free bitangents), 1,591 cylinders, 49 stored (0.77 bytes per cylinder)
//!   history  absent
//!   checksum         4 bytes  CRC-32 0xd1d3a00d
//! ```
//!
//! `N stored`: a version-3 (or 4) file stores only the `3n + 1` cylinders at θ = 0 and the
//! reader replays the others from the vertices; versions 1 and 2 store every cylinder.
//!
//! With a history (`vcx build --history always`) its line reads `history  B bytes  N nodes,
//! L links, depth D (b bytes per node)`, the depth being the longest root-to-leaf path of
//! the decoded DAG (`History::stats`).
//!
//! A file pruned to a region (`vcx build --region`, format version 4, or 2 with
//! `--explicit-cylinders`) has a line `region   viewpoints in X0,Y0,X1,Y1 only (a pruned
//! complex)` after the first. Version 4 stores the whole complex and a kept map: its
//! complex line reads `complex  B bytes  V' of V vertices and C' of C cylinders kept, N
//! stored (b bytes per kept cylinder)`, the reader replaying all `C` and keeping `C'`.
//!
//! With `--json` one object: `file`, `version`, `bytes`, `seed` (or null), `compacted`,
//! `region` (`[x0, y0, x1, y1]`, or null), `parts` — `header`, `scene`, `complex` (with
//! `vertices`, `cylinders` and `stored_cylinders` — the kept ones in a region file — and
//! `replayed_vertices`, `replayed_cylinders`: the whole complex's in version 4, else
//! null), `history` (null when absent; else
//! `bytes`, `nodes`, `links`, `depth`), `checksum` — each with its `bytes` and its counts,
//! and `checksum_value` as a hex string.

use std::path::PathBuf;

use serde_json::{json, Value};
use vcx::format::{Header, Part, CHECKSUM_LEN, HEADER_LEN};

use super::{write_stdout, Failure};

/// Arguments of `vcx inspect`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The binary complex file (written by `vcx build SCENE.json -o FILE.vcx`).
    pub file: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `1234567` as `1,234,567`.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// What `vcx inspect` reports of a file besides its length.
pub(crate) struct Described {
    /// The header (counts and part lengths).
    pub header: Header,
    /// The depth of the decoded history, if the file stores one.
    pub depth: Option<usize>,
    /// The stored CRC-32.
    pub crc: u32,
    /// The region the complex is pruned to (`vcx build --region`, versions 2 and 4), if any.
    pub region: Option<vcx::partition::Region>,
    /// Version 4: the whole complex's vertices and cylinders, which the reader replays.
    pub replayed: Option<(u64, u64)>,
}

/// The count of all vertices at the start of a version-4 complex part, after the region's
/// four varints (the file was decoded already, so they end).
fn replayed_vertices(bytes: &[u8], h: &Header) -> Option<u64> {
    let mut pos = h.part_range(Part::Complex).start;
    for _ in 0..4 {
        while bytes.get(pos)? & 0x80 != 0 {
            pos += 1;
        }
        pos += 1;
    }
    let mut v = 0u64;
    for shift in (0..35).step_by(7) {
        let b = *bytes.get(pos)?;
        v |= u64::from(b & 0x7f) << shift;
        pos += 1;
        if b & 0x80 == 0 {
            return Some(v);
        }
    }
    None
}

/// Decodes and validates a file's bytes and describes them (also used by `vcx bench
/// figures` on the bytes `vcx build -o` would write).
pub(crate) fn describe(bytes: &[u8]) -> Result<Described, vcx::format::FormatError> {
    let header = Header::read(bytes)?;
    let loaded = crate::input::decode_file(bytes)?;
    let depth = loaded.history.as_ref().map(|h| h.stats().depth);
    let region = loaded.complex.region();
    let crc = bytes
        .get(bytes.len().saturating_sub(CHECKSUM_LEN)..)
        .and_then(|t| <[u8; 4]>::try_from(t).ok())
        .map_or(0, u32::from_le_bytes);
    let replayed = if header.has_kept_map() {
        replayed_vertices(bytes, &header).map(|v| (v, 3 * u64::from(header.objects) + 1 + 3 * v))
    } else {
        None
    };
    Ok(Described {
        header,
        depth,
        crc,
        region,
        replayed,
    })
}

/// Reads, validates and describes the file.
pub fn run(args: &Args) -> Result<(), Failure> {
    let path = &args.file;
    let bytes = std::fs::read(path)
        .map_err(|e| Failure::bad_input(format!("cannot read {}: {e}", path.display())))?;
    let fail = |e: vcx::format::FormatError| crate::input::vcx_error(path, &e);
    let Described {
        header,
        depth,
        crc,
        region,
        replayed,
    } = describe(&bytes).map_err(fail)?;
    // The region as `x0,y0,x1,y1` in scene units (exact: the grid is 2⁻¹⁶).
    let corners = region.map(|r| {
        let ((x0, y0), (x1, y1)) = (r.min().to_f64(), r.max().to_f64());
        [x0, y0, x1, y1]
    });
    let h = &header;
    let text = if args.json {
        let v = json!({
            "file": path.display().to_string(),
            "version": h.version,
            "bytes": bytes.len(),
            "seed": h.seed,
            "compacted": h.compacted,
            "region": corners,
            "parts": {
                "header": {"bytes": HEADER_LEN},
                "scene": {
                    "bytes": h.scene_bytes,
                    "objects": h.objects,
                    "vertices": h.scene_vertices,
                },
                "complex": {
                    "bytes": h.complex_bytes,
                    "vertices": h.complex_vertices,
                    "cylinders": h.cylinders,
                    "stored_cylinders": h.stored_cylinders(),
                    "replayed_vertices": replayed.map(|r| r.0),
                    "replayed_cylinders": replayed.map(|r| r.1),
                },
                "history": if h.has_history() {
                    json!({
                        "bytes": h.history_bytes,
                        "nodes": h.history_nodes,
                        "links": h.history_links,
                        "depth": depth,
                    })
                } else {
                    Value::Null
                },
                "checksum": {"bytes": CHECKSUM_LEN},
            },
            "checksum_value": format!("{crc:#010x}"),
        });
        format!("{v}\n")
    } else {
        let per_cylinder = if h.cylinders > 0 {
            f64::from(h.complex_bytes) / f64::from(h.cylinders)
        } else {
            0.0
        };
        let range = |p: Part| {
            let r = h.part_range(p);
            grouped((r.end - r.start) as u64)
        };
        let mut t = format!(
            "{}: vcx complex format version {}, {} bytes, seed {}, history compacted: {}\n",
            path.display(),
            h.version,
            grouped(bytes.len() as u64),
            h.seed.map_or("not recorded".to_string(), |s| s.to_string()),
            if h.compacted { "yes" } else { "no" },
        );
        if let Some([x0, y0, x1, y1]) = corners {
            t.push_str(&format!(
                "  region   viewpoints in {x0},{y0},{x1},{y1} only (a pruned complex)\n"
            ));
        }
        t.push_str(&format!("  header   {:>9} bytes\n", range(Part::Header)));
        t.push_str(&format!(
            "  scene    {:>9} bytes  {} objects, {} vertices\n",
            range(Part::Scene),
            grouped(h.objects.into()),
            grouped(h.scene_vertices.into()),
        ));
        if let Some((v, c)) = replayed {
            t.push_str(&format!(
                "  complex  {:>9} bytes  {} of {} vertices and {} of {} cylinders kept, {} stored ({per_cylinder:.2} bytes per kept cylinder)\n",
                range(Part::Complex),
                grouped(h.complex_vertices.into()),
                grouped(v),
                grouped(h.cylinders.into()),
                grouped(c),
                grouped(h.stored_cylinders().into()),
            ));
        } else {
            t.push_str(&format!(
                "  complex  {:>9} bytes  {} vertices ({} free bitangents), {} cylinders, {} stored ({per_cylinder:.2} bytes per cylinder)\n",
                range(Part::Complex),
                grouped(h.complex_vertices.into()),
                grouped((h.complex_vertices / 2).into()),
                grouped(h.cylinders.into()),
                grouped(h.stored_cylinders().into()),
            ));
        }
        if h.has_history() {
            let per_node = f64::from(h.history_bytes) / f64::from(h.history_nodes.max(1));
            t.push_str(&format!(
                "  history  {:>9} bytes  {} nodes, {} links, depth {} ({per_node:.2} bytes per node)\n",
                range(Part::History),
                grouped(h.history_nodes.into()),
                grouped(h.history_links.into()),
                depth.unwrap_or(0),
            ));
        } else {
            t.push_str("  history  absent\n");
        }
        t.push_str(&format!(
            "  checksum {:>9} bytes  CRC-32 {crc:#010x}\n",
            CHECKSUM_LEN
        ));
        t
    };
    write_stdout(&text)
}
