//! Photoshop's PSD: the layer records and their channels, as Adobe's *Photoshop File
//! Formats Specification* lays them out (big-endian throughout).
//!
//! Read: RGB at 8 or 16 bits per channel; each pixel layer's rectangle, opacity,
//! visibility, blend mode and name (the Unicode `luni` name where there is one);
//! channels raw, PackBits (RLE), ZIP or ZIP with prediction; groups (the `lsct`/`lsdk`
//! section markers) flattened into their layers. Layer masks and adjustment layers'
//! settings are skipped; a file with no layer records is read as one layer, its merged
//! picture. Refused, naming the variant: PSB, colour modes other than RGB, 1 or 32 bits.

use std::io::Read;

use image::{Rgba, RgbaImage};
use render::{ImageLimits, Picture, Rgba16Image};

use crate::{Artwork, Budget, Layer, LayerError, MAX_LAYERS, check_size, clipped, pixel_bytes};

const FORMAT: &str = "PSD";

fn corrupt(detail: impl Into<String>) -> LayerError {
    LayerError::Corrupt {
        format: FORMAT,
        detail: detail.into(),
    }
}

fn unsupported(detail: impl Into<String>) -> LayerError {
    LayerError::Unsupported {
        format: FORMAT,
        detail: detail.into(),
    }
}

/// A big-endian reader over a byte slice that never reads past its end.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, at: 0 }
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], LayerError> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&end| end <= self.bytes.len())
            .ok_or_else(|| corrupt(format!("it ends inside {what} (byte {})", self.at)))?;
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], LayerError> {
        let mut out = [0; N];
        out.copy_from_slice(self.take(N, what)?);
        Ok(out)
    }

    fn u8(&mut self, what: &str) -> Result<u8, LayerError> {
        Ok(self.array::<1>(what)?[0])
    }

    fn u16(&mut self, what: &str) -> Result<u16, LayerError> {
        Ok(u16::from_be_bytes(self.array(what)?))
    }

    fn i16(&mut self, what: &str) -> Result<i16, LayerError> {
        Ok(i16::from_be_bytes(self.array(what)?))
    }

    fn u32(&mut self, what: &str) -> Result<u32, LayerError> {
        Ok(u32::from_be_bytes(self.array(what)?))
    }

    fn i32(&mut self, what: &str) -> Result<i32, LayerError> {
        Ok(i32::from_be_bytes(self.array(what)?))
    }

    /// A block preceded by its 32-bit length.
    fn block(&mut self, what: &str) -> Result<Cursor<'a>, LayerError> {
        let len = self.u32(what)? as usize;
        Ok(Cursor::new(self.take(len, what)?))
    }

    fn is_empty(&self) -> bool {
        self.at >= self.bytes.len()
    }
}

/// One channel of a layer record: its id (0–2 colour, −1 alpha, −2/−3 masks) and its
/// data's length (with the 2-byte compression tag).
struct Channel {
    id: i16,
    len: usize,
}

/// A layer record: what the channel data is read with.
struct Record {
    name: String,
    top: i32,
    left: i32,
    bottom: i32,
    right: i32,
    channels: Vec<Channel>,
    blend: [u8; 4],
    opacity: u8,
    hidden: bool,
    /// The section marker (`lsct`): 1 or 2 opens a group (read bottom up: its end), 3
    /// closes one (its bottom).
    section: u32,
}

/// Reads a PSD (see the module's documentation).
pub(crate) fn decode(bytes: &[u8], limits: &ImageLimits) -> Result<Artwork, LayerError> {
    let mut file = Cursor::new(bytes);
    if file.take(4, "the header")? != b"8BPS" {
        return Err(corrupt("no PSD signature"));
    }
    match file.u16("the header")? {
        1 => {}
        2 => return Err(unsupported("PSB (the large document format)")),
        v => return Err(corrupt(format!("unknown version {v}"))),
    }
    file.take(6, "the header")?;
    let channels = file.u16("the header")?;
    let height = file.u32("the header")?;
    let width = file.u32("the header")?;
    let depth = file.u16("the header")?;
    let mode = file.u16("the header")?;
    match mode {
        3 => {}
        0 => return Err(unsupported("bitmap colour mode")),
        1 => return Err(unsupported("grayscale colour mode")),
        2 => return Err(unsupported("indexed colour mode")),
        4 => return Err(unsupported("CMYK colour mode")),
        7 => return Err(unsupported("multichannel colour mode")),
        8 => return Err(unsupported("duotone colour mode")),
        9 => return Err(unsupported("Lab colour mode")),
        m => return Err(corrupt(format!("unknown colour mode {m}"))),
    }
    let bits = match depth {
        8 => 8u8,
        16 => 16,
        32 => return Err(unsupported("32 bits per channel (floating point)")),
        1 => return Err(unsupported("1 bit per channel")),
        d => return Err(corrupt(format!("{d} bits per channel"))),
    };
    if width == 0 || height == 0 {
        return Err(corrupt(format!("an empty canvas ({width} × {height})")));
    }
    check_size("the canvas", width.into(), height.into(), limits)?;
    file.block("the colour mode data")?;
    file.block("the image resources")?;
    let mut info = file.block("the layer and mask information")?;
    let mut budget = Budget::new(limits);
    let canvas = (width, height);

    let mut layers = Vec::new();
    let mut blended = Vec::new();
    let mut has_records = false;
    if !info.is_empty() {
        let mut layer_info = info.block("the layer information")?;
        if !layer_info.is_empty() {
            let count = usize::from(layer_info.i16("the layer count")?.unsigned_abs());
            has_records = count > 0;
            if count > MAX_LAYERS {
                return Err(LayerError::TooManyLayers {
                    count,
                    max: MAX_LAYERS,
                });
            }
            let records = (0..count)
                .map(|_| record(&mut layer_info))
                .collect::<Result<Vec<_>, _>>()?;
            layers = read_layers(records, &mut layer_info, bits, canvas, limits, &mut budget)?;
            blended = layers
                .iter()
                .filter(|(_, blend)| !matches!(blend, b"norm" | b"pass"))
                .map(|(layer, blend)| {
                    format!("{:?} ({})", layer.name, String::from_utf8_lossy(blend))
                })
                .collect();
        }
    }
    let mut layers: Vec<Layer> = layers.into_iter().map(|(layer, _)| layer).collect();
    if !has_records {
        // No layer records: the merged picture is the one layer.
        let merged = merged(&mut file, channels, bits, canvas, &mut budget)?;
        layers.extend(clipped(
            "Background".to_owned(),
            (0, 0),
            1.0,
            true,
            merged,
            canvas,
        ));
    }
    Ok(Artwork {
        width,
        height,
        layers,
        notes: crate::blend_notes(&blended),
    })
}

/// Reads one layer record.
fn record(c: &mut Cursor) -> Result<Record, LayerError> {
    let what = "a layer record";
    let (top, left, bottom, right) = (c.i32(what)?, c.i32(what)?, c.i32(what)?, c.i32(what)?);
    let count = c.u16(what)?;
    if count > 56 {
        return Err(corrupt(format!("a layer with {count} channels")));
    }
    let channels = (0..count)
        .map(|_| {
            Ok(Channel {
                id: c.i16(what)?,
                len: c.u32(what)? as usize,
            })
        })
        .collect::<Result<Vec<_>, LayerError>>()?;
    if c.take(4, what)? != b"8BIM" {
        return Err(corrupt("a layer record without its blend mode signature"));
    }
    let blend = c.array::<4>(what)?;
    let opacity = c.u8(what)?;
    let _clipping = c.u8(what)?;
    let flags = c.u8(what)?;
    let _filler = c.u8(what)?;
    let mut extra = c.block("a layer's extra data")?;
    extra.block("a layer mask")?;
    extra.block("a layer's blending ranges")?;
    let name_len = usize::from(extra.u8("a layer name")?);
    let name = extra.take(name_len, "a layer name")?;
    // The Pascal string is padded to a multiple of four bytes, its length byte counted.
    let padding = (4 - (name_len + 1) % 4) % 4;
    extra.take(padding.min(extra.bytes.len() - extra.at), "a layer name")?;
    let mut name = decode_name(name);
    let mut section = 0;
    while extra.bytes.len() - extra.at >= 12 {
        let signature = extra.array::<4>("additional layer information")?;
        if &signature != b"8BIM" && &signature != b"8B64" {
            break;
        }
        let key = extra.array::<4>("additional layer information")?;
        let mut data = extra.block("additional layer information")?;
        match &key {
            b"luni" => {
                let units = data.u32("a Unicode layer name")? as usize;
                let raw = data.take(units.saturating_mul(2), "a Unicode layer name")?;
                let utf16: Vec<u16> = raw
                    .chunks_exact(2)
                    .map(|b| u16::from_be_bytes([b[0], b[1]]))
                    .collect();
                name = String::from_utf16_lossy(&utf16)
                    .trim_end_matches('\0')
                    .to_owned();
            }
            b"lsct" | b"lsdk" => section = data.u32("a section marker")?,
            _ => {}
        }
    }
    Ok(Record {
        name,
        top,
        left,
        bottom,
        right,
        channels,
        blend,
        opacity,
        hidden: flags & 0x02 != 0,
        section,
    })
}

/// A layer name in the file's 8-bit encoding: UTF-8 where it is, else each byte as
/// the Latin-1 character it names.
fn decode_name(bytes: &[u8]) -> String {
    std::str::from_utf8(bytes).map_or_else(
        |_| bytes.iter().map(|&b| char::from(b)).collect(),
        str::to_owned,
    )
}

/// A group being read (bottom up): the layers read so far inside it.
struct Group {
    layers: Vec<(Layer, [u8; 4])>,
}

/// Reads every record's channel data and turns the records into layers, groups
/// flattened.
fn read_layers(
    records: Vec<Record>,
    data: &mut Cursor,
    bits: u8,
    canvas: (u32, u32),
    limits: &ImageLimits,
    budget: &mut Budget,
) -> Result<Vec<(Layer, [u8; 4])>, LayerError> {
    let mut stack = vec![Group { layers: Vec::new() }];
    for record in records {
        let width = i64::from(record.right) - i64::from(record.left);
        let height = i64::from(record.bottom) - i64::from(record.top);
        if width < 0 || height < 0 {
            return Err(corrupt(format!(
                "layer {:?} has a negative size ({width} × {height})",
                record.name
            )));
        }
        let (width, height) = (width as u64, height as u64);
        check_size(&format!("layer {:?}", record.name), width, height, limits)?;
        let mut planes: [Option<Vec<u16>>; 4] = Default::default();
        for channel in &record.channels {
            let bytes = data.take(channel.len, "a layer's channel data")?;
            let plane = match channel.id {
                0..=2 => usize::try_from(channel.id).unwrap_or(0),
                -1 => 3,
                // Masks (−2, −3) and anything else: skipped.
                _ => continue,
            };
            budget.take(width * height * 2)?;
            planes[plane] = Some(channel_plane(bytes, width as u32, height as u32, bits)?);
        }
        match record.section {
            // The bottom of a group (its end marker, read first).
            3 => {
                stack.push(Group { layers: Vec::new() });
                continue;
            }
            // The group itself, above its layers.
            1 | 2 => {
                if stack.len() < 2 {
                    return Err(corrupt(format!(
                        "group {:?} closes a group that was never opened",
                        record.name
                    )));
                }
                let group = stack.pop().unwrap_or(Group { layers: Vec::new() });
                let opacity = f32::from(record.opacity) / 255.0;
                let mut parent = stack.last_mut().map(|g| &mut g.layers);
                for (mut layer, blend) in group.layers {
                    layer.visible &= !record.hidden;
                    layer.opacity *= opacity;
                    if let Some(parent) = parent.as_deref_mut() {
                        parent.push((layer, blend));
                    }
                }
                continue;
            }
            _ => {}
        }
        if width == 0 || height == 0 {
            continue;
        }
        budget.take(pixel_bytes(width * height, bits))?;
        let picture = interleave(&planes, width as u32, height as u32, bits);
        let opacity = f32::from(record.opacity) / 255.0;
        let at = (i64::from(record.left), i64::from(record.top));
        if let Some(layer) = clipped(record.name, at, opacity, !record.hidden, picture, canvas)
            && let Some(group) = stack.last_mut()
        {
            group.layers.push((layer, record.blend));
        }
    }
    if stack.len() != 1 {
        return Err(corrupt("a group is never closed"));
    }
    Ok(stack.pop().map(|g| g.layers).unwrap_or_default())
}

/// The RGBA picture of a layer's planes (a missing alpha plane is opaque, a missing
/// colour plane black).
fn interleave(planes: &[Option<Vec<u16>>; 4], width: u32, height: u32, bits: u8) -> Picture {
    let n = width as usize * height as usize;
    let full = if bits == 8 { 255 } else { u16::MAX };
    let sample =
        |plane: usize, i: usize, default: u16| planes[plane].as_ref().map_or(default, |p| p[i]);
    let at = |x: u32, y: u32| y as usize * width as usize + x as usize;
    debug_assert!(planes.iter().flatten().all(|p| p.len() == n));
    if bits == 8 {
        Picture::Rgba8(RgbaImage::from_fn(width, height, |x, y| {
            let i = at(x, y);
            Rgba([
                sample(0, i, 0) as u8,
                sample(1, i, 0) as u8,
                sample(2, i, 0) as u8,
                sample(3, i, full) as u8,
            ])
        }))
    } else {
        Picture::Rgba16(Rgba16Image::from_fn(width, height, |x, y| {
            let i = at(x, y);
            Rgba([
                sample(0, i, 0),
                sample(1, i, 0),
                sample(2, i, 0),
                sample(3, i, full),
            ])
        }))
    }
}

/// One channel's samples (`width` × `height`, row by row) from its data: the
/// compression tag, then raw, PackBits or ZIP data.
fn channel_plane(bytes: &[u8], width: u32, height: u32, bits: u8) -> Result<Vec<u16>, LayerError> {
    let mut c = Cursor::new(bytes);
    let compression = c.u16("a channel")?;
    let rest = &bytes[2..];
    let row_bytes = width as usize * usize::from(bits / 8);
    let size = row_bytes * height as usize;
    let raw = match compression {
        0 => rest
            .get(..size)
            .ok_or_else(|| corrupt("a raw channel ends early"))?
            .to_vec(),
        1 => unpack_bits(rest, row_bytes, height as usize)?,
        2 | 3 => {
            let mut out = Vec::with_capacity(size);
            flate2::read::ZlibDecoder::new(rest)
                .take(size as u64)
                .read_to_end(&mut out)
                .map_err(|e| corrupt(format!("a ZIP channel: {e}")))?;
            if out.len() != size {
                return Err(corrupt("a ZIP channel ends early"));
            }
            if compression == 3 {
                undo_prediction(&mut out, row_bytes, bits);
            }
            out
        }
        other => return Err(corrupt(format!("unknown channel compression {other}"))),
    };
    Ok(if bits == 8 {
        raw.into_iter().map(u16::from).collect()
    } else {
        raw.chunks_exact(2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
            .collect()
    })
}

/// PackBits rows: a table of each row's compressed length (16 bits), then the rows.
fn unpack_bits(bytes: &[u8], row_bytes: usize, rows: usize) -> Result<Vec<u8>, LayerError> {
    let mut c = Cursor::new(bytes);
    let lengths = (0..rows)
        .map(|_| c.u16("a PackBits row table").map(usize::from))
        .collect::<Result<Vec<_>, _>>()?;
    let mut out = Vec::with_capacity(row_bytes * rows);
    for len in lengths {
        let row = c.take(len, "a PackBits row")?;
        let start = out.len();
        unpack_row(row, &mut out, start + row_bytes)?;
        if out.len() != start + row_bytes {
            return Err(corrupt("a PackBits row is shorter than the layer"));
        }
    }
    Ok(out)
}

/// One PackBits row into `out`, never past `end`.
fn unpack_row(row: &[u8], out: &mut Vec<u8>, end: usize) -> Result<(), LayerError> {
    let mut i = 0;
    while i < row.len() {
        let n = row[i] as i8;
        i += 1;
        match n {
            0..=127 => {
                let count = n as usize + 1;
                let literal = row
                    .get(i..i + count)
                    .ok_or_else(|| corrupt("a PackBits run ends early"))?;
                out.extend_from_slice(literal);
                i += count;
            }
            -127..=-1 => {
                let count = usize::from(n.unsigned_abs()) + 1;
                let &value = row
                    .get(i)
                    .ok_or_else(|| corrupt("a PackBits run ends early"))?;
                out.extend(std::iter::repeat_n(value, count));
                i += 1;
            }
            // −128 is a no-op.
            _ => {}
        }
        if out.len() > end {
            return Err(corrupt("a PackBits row is longer than the layer"));
        }
    }
    Ok(())
}

/// Undoes ZIP-with-prediction's horizontal differences (per row, per sample).
fn undo_prediction(data: &mut [u8], row_bytes: usize, bits: u8) {
    if row_bytes == 0 {
        return;
    }
    for row in data.chunks_exact_mut(row_bytes) {
        if bits == 8 {
            for i in 1..row.len() {
                row[i] = row[i].wrapping_add(row[i - 1]);
            }
        } else {
            let mut previous = 0u16;
            for pair in row.chunks_exact_mut(2) {
                let value = u16::from_be_bytes([pair[0], pair[1]]).wrapping_add(previous);
                pair.copy_from_slice(&value.to_be_bytes());
                previous = value;
            }
        }
    }
}

/// The merged picture at the end of the file (for files with no layer records).
fn merged(
    file: &mut Cursor,
    channels: u16,
    bits: u8,
    (width, height): (u32, u32),
    budget: &mut Budget,
) -> Result<Picture, LayerError> {
    let compression = file.u16("the merged picture")?;
    let rest = &file.bytes[file.at..];
    let row_bytes = width as usize * usize::from(bits / 8);
    let planes_count = usize::from(channels.min(4));
    let rows = height as usize * usize::from(channels);
    budget.take(pixel_bytes(u64::from(width) * u64::from(height), bits) * 2)?;
    let raw = match compression {
        0 => rest
            .get(..row_bytes * height as usize * planes_count)
            .ok_or_else(|| corrupt("the merged picture ends early"))?
            .to_vec(),
        1 => {
            // The row table covers every channel; decode the first four.
            let mut c = Cursor::new(rest);
            let lengths = (0..rows)
                .map(|_| c.u16("the merged picture's row table").map(usize::from))
                .collect::<Result<Vec<_>, _>>()?;
            let mut out = Vec::with_capacity(row_bytes * height as usize * planes_count);
            for &len in lengths.iter().take(height as usize * planes_count) {
                let row = c.take(len, "the merged picture")?;
                let start = out.len();
                unpack_row(row, &mut out, start + row_bytes)?;
                if out.len() != start + row_bytes {
                    return Err(corrupt("a merged picture's row is short"));
                }
            }
            out
        }
        other => {
            return Err(unsupported(format!("merged picture compression {other}")));
        }
    };
    let plane_len = row_bytes * height as usize;
    let mut planes: [Option<Vec<u16>>; 4] = Default::default();
    for (i, plane) in planes.iter_mut().enumerate().take(planes_count) {
        let bytes = &raw[i * plane_len..(i + 1) * plane_len];
        *plane = Some(if bits == 8 {
            bytes.iter().copied().map(u16::from).collect()
        } else {
            bytes
                .chunks_exact(2)
                .map(|b| u16::from_be_bytes([b[0], b[1]]))
                .collect()
        });
    }
    Ok(interleave(&planes, width, height, bits))
}
