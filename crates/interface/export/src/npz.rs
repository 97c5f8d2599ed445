//! `.npz` writer: a zip archive with one stored `<name>.npy` entry per variable, which is what
//! `numpy.savez` writes and `numpy.load` reads.
//!
//! Each entry follows the `.npy` format of NumPy's NEP 1 ("A Simple File Format for NumPy
//! Arrays"), version 1.0: the magic string `\x93NUMPY`, the bytes 1 and 0 (version), a
//! little-endian `u16` header length, then the header, an ASCII Python dict literal with keys
//! 'descr', 'fortran_order' and 'shape', padded with spaces and ended by a newline so that the
//! data starts at a multiple of 64 bytes (as NumPy itself writes), then the raw data in C
//! (row-major) order.

use std::io::{self, Seek, Write};

use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipWriter};

use crate::{ExportError, Matrix, Names};

const MAGIC: &[u8] = b"\x93NUMPY";

/// The `.npy` preamble and header for an array of dtype `descr` and the given shape.
pub(crate) fn npy_header(descr: &str, shape: &[usize]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    let shape = match dims.as_slice() {
        [n] => format!("({n},)"),
        _ => format!("({})", dims.join(", ")),
    };
    let dict = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    let total = (MAGIC.len() + 4 + dict.len() + 1).next_multiple_of(64);
    // The dict holds a short dtype and at most two numbers: far below u16::MAX bytes.
    let header_len = (total - MAGIC.len() - 4) as u16;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&header_len.to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.resize(total - 1, b' ');
    out.push(b'\n');
    out
}

/// A matrix as `.npy`: dtype `<f8`, shape (rows, cols), row-major data.
pub(crate) fn matrix_npy(m: &Matrix) -> Vec<u8> {
    let mut out = npy_header("<f8", &[m.rows, m.cols]);
    for v in m.data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// A name list as `.npy`: dtype `<U{maxlen}` (UTF-32 code points, zero-padded; at least 1,
/// since NumPy cannot read a zero-sized dtype), shape (n,).
pub(crate) fn names_npy(n: &Names) -> Vec<u8> {
    let width = n
        .items
        .iter()
        .map(|s| s.chars().count())
        .max()
        .unwrap_or(0)
        .max(1);
    let mut out = npy_header(&format!("<U{width}"), &[n.items.len()]);
    for item in n.items {
        let start = out.len();
        for c in item.chars() {
            out.extend_from_slice(&u32::from(c).to_le_bytes());
        }
        out.resize(start + 4 * width, 0);
    }
    out
}

/// Writes the archive; the input has been validated.
///
/// The archive is assembled in memory and then written to `w` in one piece. The zip
/// crate's `ZipWriter` finishes its archive when dropped, and when that fails (a full disk,
/// a file-size limit) it prints a debug line (`ZipWriter::drop: ...`) on stderr before the
/// caller's one-line error. Into memory, no write of the `ZipWriter` can fail; `w`'s own
/// errors come back here as ordinary errors.
pub(crate) fn write<W: Write + Seek>(
    mut w: W,
    matrices: &[Matrix],
    names: &[Names],
) -> Result<(), ExportError> {
    let entries = matrices
        .iter()
        .map(|m| (m.name, matrix_npy(m)))
        .chain(names.iter().map(|n| (n.name, names_npy(n))));
    let mut zip = ZipWriter::new(io::Cursor::new(Vec::new()));
    for (name, bytes) in entries {
        let options = SimpleFileOptions::default()
            .compression_method(CompressionMethod::Stored)
            .large_file(bytes.len() >= u32::MAX as usize);
        let added = zip
            .start_file(format!("{name}.npy"), options)
            .map_err(io::Error::from)
            .and_then(|()| zip.write_all(&bytes));
        if let Err(e) = added {
            // the zip crate refused the entry: the half-built archive is abandoned, and
            // forgetting it skips the drop's attempt to finish it (and its debug line)
            std::mem::forget(zip);
            return Err(e.into());
        }
    }
    let archive = zip.finish().map_err(io::Error::from)?.into_inner();
    w.write_all(&archive)?;
    w.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::write_npz;
    use std::io::{Cursor, Read};

    fn header_text(npy: &[u8]) -> &str {
        assert_eq!(&npy[..8], b"\x93NUMPY\x01\x00");
        let len = u16::from_le_bytes([npy[8], npy[9]]) as usize;
        std::str::from_utf8(&npy[10..10 + len]).unwrap()
    }

    #[test]
    fn npy_header_format() {
        let h = npy_header("<f8", &[2, 3]);
        assert_eq!(
            h.len(),
            128,
            "10-byte preamble + 60-byte dict + padding + newline"
        );
        let text = header_text(&h);
        assert_eq!(text.len(), 118);
        assert!(text.starts_with("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }"));
        assert!(text.ends_with(" \n"));
        assert_eq!(
            text.trim_end(),
            "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }"
        );

        let h = npy_header("<U9", &[4]);
        assert_eq!(
            header_text(&h).trim_end(),
            "{'descr': '<U9', 'fortran_order': False, 'shape': (4,), }"
        );
        // A header that does not fit 128 bytes grows to the next multiple of 64.
        let big = 10_usize.pow(18);
        let h = npy_header("<f8", &[big; 4]);
        assert_eq!(h.len(), 192);
        assert_eq!(*h.last().unwrap(), b'\n');
    }

    #[test]
    fn matrix_data_is_row_major() {
        let a = Matrix {
            name: "A",
            rows: 2,
            cols: 2,
            data: &[1.0, 2.0, 3.0, 4.0],
        };
        let npy = matrix_npy(&a);
        let values: Vec<f64> = npy[128..]
            .chunks(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(values, [1.0, 2.0, 3.0, 4.0]);
        let e = Matrix {
            name: "E",
            rows: 0,
            cols: 0,
            data: &[],
        };
        assert_eq!(matrix_npy(&e), npy_header("<f8", &[0, 0]));
    }

    #[test]
    fn names_are_fixed_width_utf32() {
        let items: Vec<String> = ["ab", "φ"].map(String::from).to_vec();
        let npy = names_npy(&Names {
            name: "n",
            items: &items,
        });
        assert!(
            header_text(&npy)
                .starts_with("{'descr': '<U2', 'fortran_order': False, 'shape': (2,), }")
        );
        let words: Vec<u32> = npy[128..]
            .chunks(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(words, ['a' as u32, 'b' as u32, 'φ' as u32, 0]);

        let none: Vec<String> = Vec::new();
        let npy = names_npy(&Names {
            name: "n",
            items: &none,
        });
        assert!(
            header_text(&npy)
                .starts_with("{'descr': '<U1', 'fortran_order': False, 'shape': (0,), }")
        );
        assert_eq!(npy.len(), 128);
    }

    #[test]
    fn archive_has_one_stored_entry_per_variable() {
        let a = Matrix {
            name: "A",
            rows: 1,
            cols: 2,
            data: &[0.5, -1.0],
        };
        let items = vec!["x".to_string()];
        let mut cursor = Cursor::new(Vec::new());
        write_npz(
            &mut cursor,
            &[a],
            &[Names {
                name: "states",
                items: &items,
            }],
        )
        .unwrap();

        let mut archive = zip::ZipArchive::new(cursor).unwrap();
        let names: Vec<String> = archive
            .file_names()
            .map(|n| n.unwrap().into_owned())
            .collect();
        assert_eq!(names, ["A.npy", "states.npy"]);
        let mut entry = archive.by_name("A.npy").unwrap();
        assert_eq!(entry.compression(), CompressionMethod::Stored);
        let mut bytes = Vec::new();
        entry.read_to_end(&mut bytes).unwrap();
        assert_eq!(bytes, matrix_npy(&a));
    }
}
