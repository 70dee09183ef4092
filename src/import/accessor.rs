//! Bounds-checked reading of glTF accessors.
//!
//! The glTF crate's readers trust the file: a count that runs past its
//! buffer view panics or allocates whatever the count says. Here every
//! accessor is checked against its buffer view (already checked against its
//! buffer, see [`super::buffers`]) before anything is allocated, so the
//! memory import uses is bounded by the file's size.

use glam::DMat4;
use gltf::accessor::{DataType, Dimensions};

use super::error::Fault;

/// Accessors without a buffer view (all zeros plus sparse values) are not
/// bounded by the file's size; this caps what they may ask for.
const MAX_VIEWLESS_ELEMENTS: usize = 1 << 22;

/// One accessor and what import reads it for (`"POSITION of mesh 0
/// primitive 1"`), so that every fault names both.
pub struct Use<'a, 'd> {
    pub accessor: &'a gltf::Accessor<'d>,
    pub usage: &'a str,
}

impl Use<'_, '_> {
    /// Reads VEC`N` elements as `f32` (normalized integers are mapped to
    /// [0, 1] or [-1, 1]; other integers keep their value, as
    /// KHR_mesh_quantization has it). Every value must be finite.
    pub fn vectors<const N: usize>(&self, buffers: &[Vec<u8>]) -> Result<Vec<[f32; N]>, Fault> {
        let expected = match N {
            1 => "SCALAR",
            2 => "VEC2",
            3 => "VEC3",
            _ => "VEC4",
        };
        if self.accessor.dimensions().multiplicity() != N || is_matrix(self.accessor.dimensions()) {
            return Err(self.wrong_type(expected));
        }
        let values = self.components(buffers)?;
        values
            .chunks_exact(N)
            .enumerate()
            .map(|(element, chunk)| {
                let mut vector = [0.0; N];
                for (out, &value) in vector.iter_mut().zip(chunk) {
                    *out = value as f32;
                }
                if vector.iter().all(|value| value.is_finite()) {
                    Ok(vector)
                } else {
                    Err(self.non_finite(element))
                }
            })
            .collect()
    }

    /// Reads unsigned integer indices, each of which must be below `limit`.
    pub fn indices(&self, buffers: &[Vec<u8>], limit: usize) -> Result<Vec<u32>, Fault> {
        let unsigned = matches!(
            self.accessor.data_type(),
            DataType::U8 | DataType::U16 | DataType::U32
        );
        if self.accessor.dimensions() != Dimensions::Scalar
            || !unsigned
            || self.accessor.normalized()
        {
            return Err(self.wrong_type("SCALAR of unsigned integers"));
        }
        let values = self.components(buffers)?;
        self.check_indices(&values, limit)?;
        Ok(values.into_iter().map(|value| value as u32).collect())
    }

    /// Reads MAT4 elements of FLOAT (inverse bind matrices), column-major
    /// as glTF stores them. Every value must be finite.
    pub fn matrices(&self, buffers: &[Vec<u8>]) -> Result<Vec<DMat4>, Fault> {
        if self.accessor.dimensions() != Dimensions::Mat4
            || self.accessor.data_type() != DataType::F32
        {
            return Err(self.wrong_type("MAT4 of FLOAT"));
        }
        let values = self.components(buffers)?;
        values
            .chunks_exact(16)
            .enumerate()
            .map(|(element, chunk)| {
                let matrix = DMat4::from_cols_slice(chunk);
                if matrix.is_finite() {
                    Ok(matrix)
                } else {
                    Err(self.non_finite(element))
                }
            })
            .collect()
    }

    /// Reads JOINTS_n: VEC4 of unsigned bytes or shorts (not normalized).
    /// Which joints exist depends on the skin of the node using the mesh,
    /// so the caller checks the values against it.
    pub fn joints(&self, buffers: &[Vec<u8>]) -> Result<Vec<[u16; 4]>, Fault> {
        let small_unsigned = matches!(self.accessor.data_type(), DataType::U8 | DataType::U16);
        if self.accessor.dimensions() != Dimensions::Vec4
            || !small_unsigned
            || self.accessor.normalized()
        {
            return Err(self.wrong_type("VEC4 of UNSIGNED_BYTE or UNSIGNED_SHORT"));
        }
        let values = self.components(buffers)?;
        // Both types fit u16 exactly.
        Ok(values
            .chunks_exact(4)
            .map(|chunk| [0, 1, 2, 3].map(|i| chunk[i] as u16))
            .collect())
    }

    /// Reads WEIGHTS_n: VEC4 of FLOAT, or of normalized unsigned bytes or
    /// shorts. Every weight must be finite and non-negative.
    pub fn weights(&self, buffers: &[Vec<u8>]) -> Result<Vec<[f32; 4]>, Fault> {
        let allowed = match self.accessor.data_type() {
            DataType::F32 => !self.accessor.normalized(),
            DataType::U8 | DataType::U16 => self.accessor.normalized(),
            _ => false,
        };
        if !allowed {
            return Err(
                self.wrong_type("VEC4 of FLOAT or of normalized UNSIGNED_BYTE or UNSIGNED_SHORT")
            );
        }
        let weights = self.vectors::<4>(buffers)?;
        match weights.iter().position(|w| w.iter().any(|&w| w < 0.0)) {
            None => Ok(weights),
            Some(element) => Err(Fault::Invalid(format!(
                "accessor {} ({}) holds a negative weight in element {element}",
                self.accessor.index(),
                self.usage
            ))),
        }
    }

    fn check_indices(&self, values: &[f64], limit: usize) -> Result<(), Fault> {
        match values.iter().position(|&value| value >= limit as f64) {
            None => Ok(()),
            Some(element) => Err(Fault::IndexOutOfRange {
                accessor: self.accessor.index(),
                usage: self.usage.to_owned(),
                element,
                index: values[element] as u64,
                limit,
            }),
        }
    }

    fn non_finite(&self, element: usize) -> Fault {
        Fault::NonFinite {
            accessor: self.accessor.index(),
            usage: self.usage.to_owned(),
            element,
        }
    }

    fn wrong_type(&self, expected: &'static str) -> Fault {
        let normalized = if self.accessor.normalized() {
            " normalized"
        } else {
            ""
        };
        Fault::AccessorType {
            accessor: self.accessor.index(),
            usage: self.usage.to_owned(),
            found: format!(
                "{} of {}{normalized}",
                dimensions_name(self.accessor.dimensions()),
                component_name(self.accessor.data_type())
            ),
            expected,
        }
    }

    /// All components, element after element, as `f64` (exact for every
    /// glTF component type), with sparse substitution applied.
    fn components(&self, buffers: &[Vec<u8>]) -> Result<Vec<f64>, Fault> {
        let accessor = self.accessor;
        let width = accessor.dimensions().multiplicity();
        let element_size = accessor.data_type().size() * width;
        let format = Format {
            data_type: accessor.data_type(),
            normalized: accessor.normalized(),
            width,
        };
        let mut values = match accessor.view() {
            Some(view) => {
                let stride = view.stride().unwrap_or(element_size);
                let span = Span {
                    view,
                    start: accessor.offset(),
                    stride,
                    count: accessor.count(),
                    element_size,
                };
                format.decode(self.bytes(&span, buffers)?, stride, accessor.count())
            }
            None if accessor.count() <= MAX_VIEWLESS_ELEMENTS => {
                vec![0.0; accessor.count() * width]
            }
            None => {
                return Err(Fault::Invalid(format!(
                    "accessor {} ({}) has no buffer view and {} elements; at most {MAX_VIEWLESS_ELEMENTS} are accepted",
                    accessor.index(),
                    self.usage,
                    accessor.count()
                )))
            }
        };
        if let Some(sparse) = accessor.sparse() {
            self.apply_sparse(&sparse, format, &mut values, buffers)?;
        }
        Ok(values)
    }

    fn apply_sparse(
        &self,
        sparse: &gltf::accessor::sparse::Sparse,
        format: Format,
        values: &mut [f64],
        buffers: &[Vec<u8>],
    ) -> Result<(), Fault> {
        let indices = sparse.indices();
        let index_size = indices.index_type().size();
        let index_span = Span {
            view: indices.view(),
            start: indices.offset(),
            stride: index_size,
            count: sparse.count(),
            element_size: index_size,
        };
        let index_format = Format {
            data_type: match indices.index_type() {
                gltf::accessor::sparse::IndexType::U8 => DataType::U8,
                gltf::accessor::sparse::IndexType::U16 => DataType::U16,
                gltf::accessor::sparse::IndexType::U32 => DataType::U32,
            },
            normalized: false,
            width: 1,
        };
        let targets = index_format.decode(
            self.bytes(&index_span, buffers)?,
            index_size,
            sparse.count(),
        );
        self.check_indices(&targets, self.accessor.count())?;

        let element_size = format.data_type.size() * format.width;
        let value_span = Span {
            view: sparse.values().view(),
            start: sparse.values().offset(),
            stride: element_size,
            count: sparse.count(),
            element_size,
        };
        let replacements = format.decode(
            self.bytes(&value_span, buffers)?,
            element_size,
            sparse.count(),
        );
        for (&target, replacement) in targets.iter().zip(replacements.chunks_exact(format.width)) {
            let at = target as usize * format.width;
            values[at..at + format.width].copy_from_slice(replacement);
        }
        Ok(())
    }

    /// The bytes `span` reads, after checking that they lie in its view.
    fn bytes<'b>(&self, span: &Span, buffers: &'b [Vec<u8>]) -> Result<&'b [u8], Fault> {
        let view = &span.view;
        let needed = match span.count {
            0 => Some(0),
            count => (count - 1)
                .checked_mul(span.stride)
                .and_then(|body| body.checked_add(span.element_size)),
        };
        let end = needed.and_then(|needed| needed.checked_add(span.start));
        match end {
            Some(end) if end <= view.length() => {
                let base = view.offset();
                Ok(&buffers[view.buffer().index()][base + span.start..base + end])
            }
            _ => Err(Fault::AccessorOutOfBounds {
                accessor: self.accessor.index(),
                usage: self.usage.to_owned(),
                start: span.start,
                end: end.unwrap_or(usize::MAX),
                view: view.index(),
                length: view.length(),
            }),
        }
    }
}

/// The glTF spec's name of an accessor `type`, as a user sees it in the file.
pub fn dimensions_name(dimensions: Dimensions) -> &'static str {
    match dimensions {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

/// The glTF spec's name of a `componentType`.
pub fn component_name(data_type: DataType) -> &'static str {
    match data_type {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    }
}

fn is_matrix(dimensions: Dimensions) -> bool {
    matches!(
        dimensions,
        Dimensions::Mat2 | Dimensions::Mat3 | Dimensions::Mat4
    )
}

/// A run of `count` elements in a buffer view, `stride` bytes apart.
struct Span<'d> {
    view: gltf::buffer::View<'d>,
    start: usize,
    stride: usize,
    count: usize,
    element_size: usize,
}

/// How the components of one element are stored.
#[derive(Clone, Copy)]
struct Format {
    data_type: DataType,
    normalized: bool,
    width: usize,
}

impl Format {
    /// Decodes `count` elements from `bytes` (already bounds-checked to hold
    /// them), `stride` bytes apart.
    fn decode(self, bytes: &[u8], stride: usize, count: usize) -> Vec<f64> {
        let size = self.data_type.size();
        let mut values = Vec::with_capacity(count * self.width);
        for element in 0..count {
            for component in 0..self.width {
                let at = element * stride + component * size;
                values.push(self.component(&bytes[at..at + size]));
            }
        }
        values
    }

    /// One component, with the glTF spec's normalization formulas.
    fn component(self, bytes: &[u8]) -> f64 {
        let (value, scale) = match self.data_type {
            DataType::I8 => (f64::from(bytes[0] as i8), 127.0),
            DataType::U8 => (f64::from(bytes[0]), 255.0),
            DataType::I16 => (f64::from(i16::from_le_bytes([bytes[0], bytes[1]])), 32767.0),
            DataType::U16 => (f64::from(u16::from_le_bytes([bytes[0], bytes[1]])), 65535.0),
            DataType::U32 => {
                let word = [bytes[0], bytes[1], bytes[2], bytes[3]];
                (f64::from(u32::from_le_bytes(word)), 4_294_967_295.0)
            }
            DataType::F32 => {
                let word = [bytes[0], bytes[1], bytes[2], bytes[3]];
                return f64::from(f32::from_le_bytes(word));
            }
        };
        if self.normalized {
            (value / scale).max(-1.0)
        } else {
            value
        }
    }
}
