//! NumPy arrays in and out: row-major `Vec<f64>` ↔ `float64` arrays of a given shape.

use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::errors;

/// `values` (row-major) as an array of `shape`; the caller guarantees the element count.
pub fn shaped<'py>(
    py: Python<'py>,
    values: Vec<f64>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    PyArray1::from_vec(py, values).reshape(shape)
}

/// The rows of `values` (each `width` long) padded with NaN to `rows` rows — a method's
/// estimates after a failure, so every array lines up with the times.
pub fn padded<'py>(
    py: Python<'py>,
    mut values: Vec<f64>,
    rows: usize,
    row_shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let width: usize = row_shape.iter().product();
    values.resize(rows * width, f64::NAN);
    let mut shape = vec![rows];
    shape.extend_from_slice(row_shape);
    shaped(py, values, &shape)
}

/// A 1-D or 2-D array's values row-major with its row count and width (a 1-D array is one
/// value per row), named `what` in errors.
pub fn rows(array: &PyReadonlyArrayDyn<'_, f64>, what: &str) -> PyResult<(Vec<f64>, usize, usize)> {
    let shape = array.shape().to_vec();
    let (r, w) = match shape[..] {
        [r] => (r, 1),
        [r, w] => (r, w),
        _ => {
            return Err(errors::dimension(format!(
                "{what} must be a 1-D or 2-D array, got shape {shape:?}"
            )))
        }
    };
    // An unaligned buffer (one unpickled from a protocol-5 stream, or a `frombuffer` at an odd
    // offset) cannot be read as f64 values in place: refused with the fix, never read (it
    // would be undefined behaviour; ndarray's debug assertion panics on it). The package's own
    // conversions (`_convert._array`) copy such arrays first.
    let align = core::mem::align_of::<f64>();
    let aligned = (array.data() as usize).is_multiple_of(align)
        && array
            .strides()
            .iter()
            .all(|s| s.unsigned_abs().is_multiple_of(align));
    if !aligned {
        return Err(errors::dimension(format!(
            "{what} is not aligned in memory for float64: pass numpy.require({what}, numpy.float64, 'CA')"
        )));
    }
    Ok((array.as_array().iter().copied().collect(), r, w))
}
