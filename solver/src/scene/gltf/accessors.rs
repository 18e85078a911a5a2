//! Typed reads of accessor data (positions, normals, texture coordinates,
//! indices) out of the buffers, every span checked against its view and
//! every value checked finite.

use super::container::Buffer;
use super::Context;
use crate::scene::SceneError;
use glam::{DVec2, DVec3};
use gltf::accessor::{DataType, Dimensions};

/// The bytes an accessor's elements occupy, with their stride: the accessor
/// must have a view (sparse and zero-filled accessors carry no geometry
/// here), and its last element must end inside the view.
fn accessor_span<'b>(
    ctx: &Context,
    buffers: &'b [Buffer],
    accessor: &gltf::Accessor,
    element: usize,
    what: &str,
    item: &str,
) -> Result<(&'b [u8], usize, usize), SceneError> {
    let name = format!("{what} accessor {}", accessor.index());
    if accessor.sparse().is_some() {
        return Err(ctx.err(
            item,
            format!("{name} is sparse; sparse accessors are not read for mesh geometry"),
        ));
    }
    let Some(view) = accessor.view() else {
        return Err(ctx.err(
            item,
            format!("{name} has no bufferView (all zeros), which makes no surface"),
        ));
    };
    let count = accessor.count();
    if count == 0 {
        return Err(ctx.err(item, format!("{name} has no elements")));
    }
    let stride = view.stride().unwrap_or(element);
    if stride < element {
        return Err(ctx.err(
            item,
            format!("{name}: byteStride {stride} of bufferView {} is less than its {element}-byte elements", view.index()),
        ));
    }
    let end = accessor.offset() as u64 + (count as u64 - 1) * stride as u64 + element as u64;
    if end > view.length() as u64 {
        return Err(ctx.err(
            item,
            format!(
                "{name}: {count} elements of {element} bytes at stride {stride} from byte {} \
                 need {end} bytes, but bufferView {} has {}",
                accessor.offset(),
                view.index(),
                view.length()
            ),
        ));
    }
    let buffer = buffers[view.buffer().index()].data();
    let start = view.offset() + accessor.offset();
    Ok((&buffer[start..view.offset() + end as usize], stride, count))
}

/// A `VEC3` `FLOAT` accessor (positions, normals) in f64, every value finite.
pub(super) fn read_vec3(
    ctx: &Context,
    buffers: &[Buffer],
    accessor: &gltf::Accessor,
    what: &str,
    item: &str,
) -> Result<Vec<DVec3>, SceneError> {
    if accessor.data_type() != DataType::F32
        || accessor.dimensions() != Dimensions::Vec3
        || accessor.normalized()
    {
        return Err(ctx.err(
            item,
            format!(
                "{what} accessor {} is {}; expected VEC3 of FLOAT",
                accessor.index(),
                layout(accessor)
            ),
        ));
    }
    let (bytes, stride, count) = accessor_span(ctx, buffers, accessor, 12, what, item)?;
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let e = &bytes[k * stride..k * stride + 12];
        let c = |j: usize| {
            f64::from(f32::from_le_bytes([
                e[4 * j],
                e[4 * j + 1],
                e[4 * j + 2],
                e[4 * j + 3],
            ]))
        };
        let v = DVec3::new(c(0), c(1), c(2));
        if !v.is_finite() {
            return Err(not_finite(ctx, accessor, what, item, k));
        }
        out.push(v);
    }
    Ok(out)
}

/// A `VEC2` texture-coordinate accessor in f64: `FLOAT`, or normalized
/// `UNSIGNED_BYTE` or `UNSIGNED_SHORT` (glTF 2.0 specification, §3.7.2.1),
/// every value finite.
pub(super) fn read_vec2(
    ctx: &Context,
    buffers: &[Buffer],
    accessor: &gltf::Accessor,
    what: &str,
    item: &str,
) -> Result<Vec<DVec2>, SceneError> {
    let size = match (accessor.data_type(), accessor.normalized()) {
        (DataType::F32, false) => 4,
        (DataType::U16, true) => 2,
        (DataType::U8, true) => 1,
        _ => 0,
    };
    if size == 0 || accessor.dimensions() != Dimensions::Vec2 {
        return Err(ctx.err(
            item,
            format!(
                "{what} accessor {} is {}; expected VEC2 of FLOAT, or of normalized \
                 UNSIGNED_BYTE or UNSIGNED_SHORT",
                accessor.index(),
                layout(accessor)
            ),
        ));
    }
    let (bytes, stride, count) = accessor_span(ctx, buffers, accessor, 2 * size, what, item)?;
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let e = &bytes[k * stride..k * stride + 2 * size];
        let c = |j: usize| -> f64 {
            let b = &e[j * size..(j + 1) * size];
            match size {
                4 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                2 => f64::from(u16::from_le_bytes([b[0], b[1]])) / 65535.0,
                _ => f64::from(b[0]) / 255.0,
            }
        };
        let v = DVec2::new(c(0), c(1));
        if !v.is_finite() {
            return Err(not_finite(ctx, accessor, what, item, k));
        }
        out.push(v);
    }
    Ok(out)
}

/// A `SCALAR` index accessor of unsigned bytes, shorts or ints (glTF 2.0
/// specification, §3.7.3).
pub(super) fn read_indices(
    ctx: &Context,
    buffers: &[Buffer],
    accessor: &gltf::Accessor,
    item: &str,
) -> Result<Vec<u32>, SceneError> {
    let size = match accessor.data_type() {
        DataType::U8 => 1,
        DataType::U16 => 2,
        DataType::U32 => 4,
        other => {
            return Err(ctx.err(
                item,
                format!(
                    "index accessor {} has component type {other:?}; indices are \
                     UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
                    accessor.index()
                ),
            ))
        }
    };
    if accessor.dimensions() != Dimensions::Scalar {
        return Err(ctx.err(
            item,
            format!(
                "index accessor {} is {:?}, not SCALAR",
                accessor.index(),
                accessor.dimensions()
            ),
        ));
    }
    let (bytes, stride, count) = accessor_span(ctx, buffers, accessor, size, "index", item)?;
    Ok((0..count)
        .map(|k| {
            let e = &bytes[k * stride..k * stride + size];
            match size {
                1 => u32::from(e[0]),
                2 => u32::from(u16::from_le_bytes([e[0], e[1]])),
                _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
            }
        })
        .collect())
}

/// An accessor's element layout for messages: dimensions, component type,
/// and whether it is normalized (`Vec3 F32`, `Vec2 U8 normalized`).
fn layout(accessor: &gltf::Accessor) -> String {
    format!(
        "{:?} {:?}{}",
        accessor.dimensions(),
        accessor.data_type(),
        if accessor.normalized() {
            " normalized"
        } else {
            ""
        }
    )
}

/// The error for element `k` of an accessor that is not finite.
fn not_finite(
    ctx: &Context,
    accessor: &gltf::Accessor,
    what: &str,
    item: &str,
    k: usize,
) -> SceneError {
    ctx.err(
        item,
        format!(
            "{what} accessor {}: element {k} is not finite",
            accessor.index()
        ),
    )
}
