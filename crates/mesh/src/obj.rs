//! Wavefront OBJ input and output of 2-D meshes.

use std::io::{BufRead, BufWriter, Write};

use glam::DVec2;

use crate::{Mesh, MeshError};

impl Mesh {
    /// Reads a mesh from Wavefront OBJ text.
    ///
    /// * `v x y [z [w]]`: a vertex; `z` and `w` are ignored.
    /// * `f a b c ...`: a face; indices are 1-based, negative ones count back from the
    ///   last vertex read so far (`-1` is the latest), and the `a/t`, `a/t/n`, `a//n`
    ///   forms are accepted (only the vertex index is used). Faces with more than three
    ///   vertices are fan-triangulated from their first vertex.
    /// * Comments (`#`), blank lines and every other statement (`vt`, `vn`, `o`, `g`,
    ///   `s`, `usemtl`, ...) are ignored.
    ///
    /// If the faces' total signed area is negative (a file written with the opposite
    /// winding, e.g. y up), every triangle is flipped so the result follows the crate's
    /// orientation (see [`Mesh`]). Vertices are kept in file order, unused ones included.
    ///
    /// # Errors
    /// [`MeshError::Obj`] with the 1-based line number for an unparsable or non-finite
    /// coordinate, a face with fewer than three vertices, an index of 0 or out of range,
    /// or a face that repeats a vertex index; [`MeshError::Io`] when reading fails.
    pub fn read_obj<R: BufRead>(r: R) -> Result<Mesh, MeshError> {
        let mut vertices: Vec<DVec2> = Vec::new();
        // Triangles with the line they came from, checked once all vertices are known.
        let mut faces: Vec<([i64; 3], usize)> = Vec::new();
        for (n, line) in r.lines().enumerate() {
            let line_no = n + 1;
            let line = line?;
            let err = |message: String| MeshError::Obj {
                line: line_no,
                message,
            };
            let content = line.split('#').next().unwrap_or("");
            let mut tokens = content.split_whitespace();
            match tokens.next() {
                Some("v") => {
                    let mut coords = [0.0f64; 2];
                    for (k, c) in coords.iter_mut().enumerate() {
                        let tok = tokens.next().ok_or_else(|| {
                            err(format!("vertex needs x and y, found {} value(s)", k))
                        })?;
                        *c = tok
                            .parse::<f64>()
                            .map_err(|_| err(format!("cannot parse coordinate {tok:?}")))?;
                        if !c.is_finite() {
                            return Err(err(format!("coordinate {tok:?} is not finite")));
                        }
                    }
                    for tok in tokens {
                        tok.parse::<f64>()
                            .map_err(|_| err(format!("cannot parse coordinate {tok:?}")))?;
                    }
                    vertices.push(DVec2::new(coords[0], coords[1]));
                }
                Some("f") => {
                    let mut idx: Vec<i64> = Vec::new();
                    for tok in tokens {
                        let first = tok.split('/').next().unwrap_or("");
                        let i: i64 = first
                            .parse()
                            .map_err(|_| err(format!("cannot parse vertex index {tok:?}")))?;
                        let resolved = match i {
                            0 => return Err(err("vertex index 0 (OBJ indices start at 1)".into())),
                            i if i < 0 => {
                                let r = vertices.len() as i64 + i;
                                if r < 0 {
                                    return Err(err(format!(
                                        "relative index {i} points before the first vertex"
                                    )));
                                }
                                r
                            }
                            i => i - 1,
                        };
                        idx.push(resolved);
                    }
                    if idx.len() < 3 {
                        return Err(err(format!(
                            "a face needs at least 3 vertices, found {}",
                            idx.len()
                        )));
                    }
                    for (k, a) in idx.iter().enumerate() {
                        if idx[k + 1..].contains(a) {
                            return Err(err(format!(
                                "degenerate face: vertex {} appears twice",
                                a + 1
                            )));
                        }
                    }
                    for k in 1..idx.len() - 1 {
                        faces.push(([idx[0], idx[k], idx[k + 1]], line_no));
                    }
                }
                _ => {}
            }
        }
        let n = vertices.len() as i64;
        let mut triangles = Vec::with_capacity(faces.len());
        for (f, line) in faces {
            if let Some(&bad) = f.iter().find(|&&i| i >= n || i > u32::MAX as i64) {
                return Err(MeshError::Obj {
                    line,
                    message: format!(
                        "vertex index {} out of range (file has {n} vertices)",
                        bad + 1
                    ),
                });
            }
            triangles.push(f.map(|i| i as u32));
        }
        let mut mesh = Mesh {
            vertices,
            triangles,
        };
        if mesh.area() < 0.0 {
            for t in &mut mesh.triangles {
                t.swap(1, 2);
            }
        }
        Ok(mesh)
    }

    /// Writes the mesh as Wavefront OBJ: a comment line, then `v x y 0` per vertex and
    /// `f a b c` (1-based) per triangle.
    ///
    /// Coordinates are printed in Rust's shortest round-trip form, so
    /// [`Mesh::read_obj`] gives back exactly the same mesh.
    ///
    /// # Errors
    /// Any error of the underlying writer.
    pub fn write_obj<W: Write>(&self, w: W) -> std::io::Result<()> {
        let mut w = BufWriter::new(w);
        writeln!(
            w,
            "# 2-D mesh in image pixel coordinates (x right, y down): {} vertices, {} triangles",
            self.vertices.len(),
            self.triangles.len()
        )?;
        for v in &self.vertices {
            writeln!(w, "v {} {} 0", v.x, v.y)?;
        }
        for t in &self.triangles {
            writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
        }
        w.flush()
    }
}
