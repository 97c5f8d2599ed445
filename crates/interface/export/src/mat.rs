//! Level-5 MAT-file writer, after "MAT-File Format" (MathWorks), chapter "Level 5 MAT-File
//! Format".
//!
//! Everything is little-endian. A file is a 128-byte header followed by data elements. A data
//! element is an 8-byte tag (`u32` data type, `u32` byte count of the data without padding),
//! the data, and zero padding to a multiple of 8 bytes. A variable is one `miMATRIX` element
//! whose data are sub-elements: array flags, dimensions, array name, then the class's data (the
//! real part of a numeric array, or one `miMATRIX` per cell of a cell array, unnamed).
//! Numeric data are stored in column-major order, as MATLAB holds them.

use std::io::Write;

use crate::{ExportError, Matrix, Names};

// Data types (table "MAT-File Data Types").
const MI_INT8: u32 = 1;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_DOUBLE: u32 = 9;
const MI_MATRIX: u32 = 14;
const MI_UTF16: u32 = 17;

// Array classes (table "MATLAB Array Types (Classes)").
const MX_CELL_CLASS: u8 = 1;
const MX_CHAR_CLASS: u8 = 4;
const MX_DOUBLE_CLASS: u8 = 6;

/// Descriptive text at the start of the header; the rest of its 116 bytes are spaces.
pub(crate) const HEADER_TEXT: &str = "MATLAB 5.0 MAT-file, written by pendkit";

/// A size that does not fit the format's 32-bit fields.
struct TooLarge;

/// What appends the data of one element to the buffer.
type Fill<'f> = &'f mut dyn FnMut(&mut Vec<u8>) -> Result<(), TooLarge>;

/// The 128-byte header: text, subsystem data offset (none: zeros), version 0x0100 and the
/// endian indicator, the characters 'MI' as a `u16`, which reads "IM" when little-endian.
pub(crate) fn header() -> [u8; 128] {
    let mut h = [b' '; 128];
    h[..HEADER_TEXT.len()].copy_from_slice(HEADER_TEXT.as_bytes());
    h[116..124].fill(0);
    h[124..126].copy_from_slice(&0x0100u16.to_le_bytes());
    h[126..128].copy_from_slice(b"IM");
    h
}

/// Writes header and variables; the input has been validated.
pub(crate) fn write<W: Write>(
    mut w: W,
    matrices: &[Matrix],
    names: &[Names],
) -> Result<(), ExportError> {
    w.write_all(&header())?;
    let too_large = |name: &str| ExportError::TooLarge { name: name.into() };
    for m in matrices {
        let mut buf = Vec::new();
        double_array(&mut buf, m).map_err(|TooLarge| too_large(m.name))?;
        w.write_all(&buf)?;
    }
    for n in names {
        let mut buf = Vec::new();
        cell_of_strings(&mut buf, n).map_err(|TooLarge| too_large(n.name))?;
        w.write_all(&buf)?;
    }
    w.flush()?;
    Ok(())
}

/// Appends one data element: the tag, what `fill` appends, and padding to 8 bytes.
/// `out` must end at a multiple of 8 bytes, as every element does.
fn element(out: &mut Vec<u8>, data_type: u32, fill: Fill) -> Result<(), TooLarge> {
    let start = out.len();
    out.extend_from_slice(&data_type.to_le_bytes());
    out.extend_from_slice(&[0; 4]);
    fill(out)?;
    let size = u32::try_from(out.len() - start - 8).map_err(|_| TooLarge)?;
    out[start + 4..start + 8].copy_from_slice(&size.to_le_bytes());
    out.resize(out.len().next_multiple_of(8), 0);
    Ok(())
}

fn bytes_element(out: &mut Vec<u8>, data_type: u32, bytes: &[u8]) -> Result<(), TooLarge> {
    element(out, data_type, &mut |out| {
        out.extend_from_slice(bytes);
        Ok(())
    })
}

/// Appends an `miMATRIX` element: array flags (class; not complex, global or logical),
/// dimensions, name, then the class's data from `data`.
fn array(
    out: &mut Vec<u8>,
    class: u8,
    dims: [usize; 2],
    name: &str,
    data: Fill,
) -> Result<(), TooLarge> {
    element(out, MI_MATRIX, &mut |out| {
        bytes_element(out, MI_UINT32, &[class, 0, 0, 0, 0, 0, 0, 0])?;
        let mut dim_bytes = Vec::with_capacity(8);
        for d in dims {
            let d = i32::try_from(d).map_err(|_| TooLarge)?;
            dim_bytes.extend_from_slice(&d.to_le_bytes());
        }
        bytes_element(out, MI_INT32, &dim_bytes)?;
        bytes_element(out, MI_INT8, name.as_bytes())?;
        data(out)
    })
}

/// A `rows x cols` double array, real part in column-major order.
fn double_array(out: &mut Vec<u8>, m: &Matrix) -> Result<(), TooLarge> {
    array(out, MX_DOUBLE_CLASS, [m.rows, m.cols], m.name, &mut |out| {
        element(out, MI_DOUBLE, &mut |out| {
            for c in 0..m.cols {
                for r in 0..m.rows {
                    out.extend_from_slice(&m.data[r * m.cols + c].to_le_bytes());
                }
            }
            Ok(())
        })
    })
}

/// An `n x 1` cell array whose cells are `1 x len` char arrays. Characters are UTF-16 code
/// units, as in MATLAB; `scipy.io.loadmat` reads any text in the Basic Multilingual Plane.
fn cell_of_strings(out: &mut Vec<u8>, n: &Names) -> Result<(), TooLarge> {
    array(out, MX_CELL_CLASS, [n.items.len(), 1], n.name, &mut |out| {
        for item in n.items {
            let units: Vec<u16> = item.encode_utf16().collect();
            array(out, MX_CHAR_CLASS, [1, units.len()], "", &mut |out| {
                element(out, MI_UTF16, &mut |out| {
                    units
                        .iter()
                        .for_each(|u| out.extend_from_slice(&u.to_le_bytes()));
                    Ok(())
                })
            })?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::write_mat;

    /// A variable read back by the tiny reader below.
    #[derive(Debug, PartialEq)]
    enum Var {
        /// Dimensions and values in file (column-major) order.
        Double(Vec<i32>, Vec<f64>),
        /// Dimensions and the cells' strings.
        Cell(Vec<i32>, Vec<String>),
    }

    /// Reads one element at `*pos`, checks its padding, and moves past it.
    fn read_element<'b>(bytes: &'b [u8], pos: &mut usize) -> (u32, &'b [u8]) {
        assert_eq!(*pos % 8, 0, "element at {pos} not 8-byte aligned");
        let word = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap());
        let (data_type, size) = (word(*pos), word(*pos + 4) as usize);
        let data = &bytes[*pos + 8..*pos + 8 + size];
        let end = *pos + 8 + size.next_multiple_of(8);
        assert!(
            bytes[*pos + 8 + size..end].iter().all(|&b| b == 0),
            "padding"
        );
        *pos = end;
        (data_type, data)
    }

    /// Reads an `miMATRIX` element's data: (name, variable).
    fn read_array(data: &[u8]) -> (String, Var) {
        let mut pos = 0;
        let (ty, flags) = read_element(data, &mut pos);
        assert_eq!((ty, flags.len()), (MI_UINT32, 8));
        assert_eq!(&flags[1..], &[0; 7]);
        let (ty, dims) = read_element(data, &mut pos);
        assert_eq!(ty, MI_INT32);
        let dims: Vec<i32> = dims
            .chunks(4)
            .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        let (ty, name) = read_element(data, &mut pos);
        assert_eq!(ty, MI_INT8);
        let name = String::from_utf8(name.to_vec()).unwrap();
        let var = match flags[0] {
            MX_DOUBLE_CLASS => {
                let (ty, real) = read_element(data, &mut pos);
                assert_eq!(ty, MI_DOUBLE);
                let values = real
                    .chunks(8)
                    .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                    .collect();
                Var::Double(dims, values)
            }
            MX_CELL_CLASS => {
                let mut items = Vec::new();
                while pos < data.len() {
                    let (ty, cell) = read_element(data, &mut pos);
                    assert_eq!(ty, MI_MATRIX);
                    let (cell_name, Var::Cell(cell_dims, mut text)) = read_array(cell) else {
                        panic!("cell is not a char array")
                    };
                    assert_eq!(cell_name, "");
                    assert_eq!(cell_dims[0], 1);
                    items.push(text.pop().unwrap());
                }
                Var::Cell(dims, items)
            }
            MX_CHAR_CLASS => {
                let (ty, chars) = read_element(data, &mut pos);
                assert_eq!(ty, MI_UTF16);
                let units: Vec<u16> = chars
                    .chunks(2)
                    .map(|c| u16::from_le_bytes(c.try_into().unwrap()))
                    .collect();
                assert_eq!(units.len(), dims[1] as usize);
                Var::Cell(dims, vec![String::from_utf16(&units).unwrap()])
            }
            class => panic!("unexpected class {class}"),
        };
        assert_eq!(pos, data.len(), "trailing bytes in '{name}'");
        (name, var)
    }

    /// Reads a whole file: header checks, then every variable.
    fn read_mat(bytes: &[u8]) -> Vec<(String, Var)> {
        assert_eq!(&bytes[124..128], &[0x00, 0x01, b'I', b'M']);
        let mut pos = 128;
        let mut vars = Vec::new();
        while pos < bytes.len() {
            let (ty, data) = read_element(bytes, &mut pos);
            assert_eq!(ty, MI_MATRIX);
            vars.push(read_array(data));
        }
        vars
    }

    fn mat_bytes(matrices: &[Matrix], names: &[Names]) -> Vec<u8> {
        let mut bytes = Vec::new();
        write_mat(&mut bytes, matrices, names).unwrap();
        bytes
    }

    #[test]
    fn header_layout() {
        let bytes = mat_bytes(&[], &[]);
        assert_eq!(bytes.len(), 128);
        let text = HEADER_TEXT.as_bytes();
        assert_eq!(&bytes[..text.len()], text);
        assert!(bytes[text.len()..116].iter().all(|&b| b == b' '));
        assert_eq!(&bytes[116..124], &[0; 8], "no subsystem data");
        assert_eq!(
            &bytes[124..126],
            &[0x00, 0x01],
            "version 0x0100, little-endian"
        );
        assert_eq!(&bytes[126..128], b"IM", "endian indicator");
    }

    #[test]
    fn scalar_element_bytes() {
        let x = Matrix {
            name: "x",
            rows: 1,
            cols: 1,
            data: &[1.5],
        };
        let bytes = mat_bytes(&[x], &[]);
        let mut expected = Vec::new();
        for word in [
            MI_MATRIX, 64, MI_UINT32, 8, 6, 0, MI_INT32, 8, 1, 1, MI_INT8, 1,
        ] {
            expected.extend_from_slice(&word.to_le_bytes());
        }
        expected.extend_from_slice(&[b'x', 0, 0, 0, 0, 0, 0, 0]);
        expected.extend_from_slice(&MI_DOUBLE.to_le_bytes());
        expected.extend_from_slice(&8u32.to_le_bytes());
        expected.extend_from_slice(&1.5f64.to_le_bytes());
        assert_eq!(&bytes[128..], &expected[..]);
    }

    #[test]
    fn padding_keeps_elements_aligned() {
        // A 9-character name and a 3-character string need padding; the reader checks that
        // every element starts at a multiple of 8 and that padding is zero.
        let m = Matrix {
            name: "abcdefghi",
            rows: 1,
            cols: 1,
            data: &[2.0],
        };
        let items = vec!["abc".to_string()];
        let bytes = mat_bytes(
            &[m],
            &[Names {
                name: "n",
                items: &items,
            }],
        );
        assert_eq!(bytes.len() % 8, 0);
        let name_tag = 128 + 8 + 16 + 16;
        assert_eq!(&bytes[name_tag..name_tag + 8], &[1, 0, 0, 0, 9, 0, 0, 0]);
        assert_eq!(
            &bytes[name_tag + 8..name_tag + 24],
            b"abcdefghi\0\0\0\0\0\0\0"
        );
        assert_eq!(read_mat(&bytes).len(), 2);
    }

    #[test]
    fn data_is_column_major() {
        let a = Matrix {
            name: "A",
            rows: 2,
            cols: 3,
            data: &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
        };
        let b = Matrix {
            name: "B",
            rows: 3,
            cols: 1,
            data: &[7.0, 8.0, 9.0],
        };
        let vars = read_mat(&mat_bytes(&[a, b], &[]));
        assert_eq!(
            vars,
            vec![
                (
                    "A".into(),
                    Var::Double(vec![2, 3], vec![1.0, 4.0, 2.0, 5.0, 3.0, 6.0])
                ),
                ("B".into(), Var::Double(vec![3, 1], vec![7.0, 8.0, 9.0])),
            ]
        );
    }

    #[test]
    fn names_become_cells_of_char_arrays() {
        let states: Vec<String> = ["x1", "theta_dot", "φ", ""].map(String::from).to_vec();
        let none: Vec<String> = Vec::new();
        let names = [
            Names {
                name: "states",
                items: &states,
            },
            Names {
                name: "inputs",
                items: &none,
            },
        ];
        let vars = read_mat(&mat_bytes(&[], &names));
        assert_eq!(
            vars,
            vec![
                ("states".into(), Var::Cell(vec![4, 1], states.clone())),
                ("inputs".into(), Var::Cell(vec![0, 1], vec![])),
            ]
        );
    }

    #[test]
    fn empty_matrices() {
        let e = Matrix {
            name: "E",
            rows: 0,
            cols: 0,
            data: &[],
        };
        let z = Matrix {
            name: "Z",
            rows: 2,
            cols: 0,
            data: &[],
        };
        let vars = read_mat(&mat_bytes(&[e, z], &[]));
        assert_eq!(
            vars,
            vec![
                ("E".into(), Var::Double(vec![0, 0], vec![])),
                ("Z".into(), Var::Double(vec![2, 0], vec![])),
            ]
        );
    }

    #[test]
    fn oversized_dimensions_are_an_error() {
        let big = Matrix {
            name: "big",
            rows: 1 << 31,
            cols: 0,
            data: &[],
        };
        let err = write_mat(Vec::new(), &[big], &[]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "variable 'big' is too large for a level-5 MAT-file (4 GiB per variable)"
        );
    }
}
