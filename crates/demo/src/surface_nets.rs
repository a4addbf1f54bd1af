//! Naive surface nets (Gibson 1998): the zero set of the body's field as a closed,
//! 2-manifold, counter-clockwise triangle mesh, then one Newton step onto the surface.

use glam::Vec3;

use crate::body::{Body, FAR};
/// Polygonizes the zero set of `body` on its grid: shared vertices and counter-clockwise
/// (seen from outside, where the field is positive) triangles.
pub(crate) fn surface_nets(body: &Body) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let [nx, ny, nz] = body.dims;
    let (cx, cz) = (nx - 1, nz - 1);
    let mut lower = vec![FAR; nx * nz];
    let mut upper = vec![FAR; nx * nz];
    // `lower < 0`, `upper < 0`: inside.
    let mut in_lower = vec![false; nx * nz];
    let mut in_upper = vec![false; nx * nz];
    // Per row `k` of a slice, the first and last `i` of an inside point, `(usize::MAX, 0)`
    // if none: most of the grid is outside, and only rows and spans near inside points can
    // hold crossings.
    let mut spans_lower = vec![(usize::MAX, 0); nz];
    let mut spans_upper = vec![(usize::MAX, 0); nz];
    let classify = |field: &[f32], inside: &mut [bool], spans: &mut [(usize, usize)]| {
        inside
            .iter_mut()
            .zip(field)
            .for_each(|(b, v)| *b = *v < 0.0);
        for (row, span) in inside.chunks_exact(nx).zip(spans) {
            let first = row.iter().position(|b| *b);
            let last = row.iter().rposition(|b| *b);
            *span = (first.unwrap_or(usize::MAX), last.unwrap_or(0));
        }
    };
    // Vertex of each cell in the previous and the current cell layer (u32::MAX: none).
    let mut prev = vec![u32::MAX; cx * cz];
    let mut cur = vec![u32::MAX; cx * cz];
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    body.eval_slice(0, &mut lower);
    classify(&lower, &mut in_lower, &mut spans_lower);
    for j in 0..ny - 1 {
        body.eval_slice(j + 1, &mut upper);
        classify(&upper, &mut in_upper, &mut spans_upper);
        remove_ambiguous_faces(
            nx,
            &in_lower,
            &spans_lower,
            &mut upper,
            &mut in_upper,
            &spans_upper,
        );
        // Cell vertices of layer j (between slices j and j + 1). Corner `c` of a cell is
        // at offset `(c & 1, c >> 1 & 1, c >> 2 & 1)`.
        cur.fill(u32::MAX);
        for k in 0..cz {
            let (lo, hi) = union(&[
                spans_lower[k],
                spans_lower[k + 1],
                spans_upper[k],
                spans_upper[k + 1],
            ]);
            // Cell i has corners i and i + 1.
            for i in lo.saturating_sub(1)..=hi.min(cx - 1) {
                let (p0, p1) = (i + nx * k, i + nx * (k + 1));
                let mask = in_lower[p0] as u8
                    | (in_lower[p0 + 1] as u8) << 1
                    | (in_upper[p0] as u8) << 2
                    | (in_upper[p0 + 1] as u8) << 3
                    | (in_lower[p1] as u8) << 4
                    | (in_lower[p1 + 1] as u8) << 5
                    | (in_upper[p1] as u8) << 6
                    | (in_upper[p1 + 1] as u8) << 7;
                if mask == 0 || mask == u8::MAX {
                    continue;
                }
                let corner = [
                    lower[p0],
                    lower[p0 + 1],
                    upper[p0],
                    upper[p0 + 1],
                    lower[p1],
                    lower[p1 + 1],
                    upper[p1],
                    upper[p1 + 1],
                ];
                let mut sum = Vec3::ZERO;
                let mut count = 0.0f32;
                for c in 0..8 {
                    for bit in [1, 2, 4] {
                        let d = c | bit;
                        if c & bit != 0 || (mask >> c & 1) == (mask >> d & 1) {
                            continue;
                        }
                        // Keep crossings off the corners so that vertices of neighbouring
                        // cells never coincide (no zero-area triangles).
                        let t = (corner[c] / (corner[c] - corner[d])).clamp(0.01, 0.99);
                        let offset = |b: usize| ((c & b) != 0) as u8 as f32;
                        let mut q = Vec3::new(offset(1), offset(2), offset(4));
                        match bit {
                            1 => q.x = t,
                            2 => q.y = t,
                            _ => q.z = t,
                        }
                        sum += q;
                        count += 1.0;
                    }
                }
                let local = Vec3::new(i as f32, j as f32, k as f32) + sum / count;
                cur[i + cx * k] = positions.len() as u32;
                positions.push(body.origin + local * body.cell);
            }
        }
        let cell = |layer: &[u32], i: usize, k: usize| layer[i + cx * k];
        // Edges along y between slices j and j + 1: the 4 cells around are in layer j.
        for k in 1..nz - 1 {
            let (lo, hi) = union(&[spans_lower[k], spans_upper[k]]);
            for i in lo.max(1)..=hi.min(nx - 2) {
                let (a, b) = (in_lower[i + nx * k], in_upper[i + nx * k]);
                if a != b {
                    let quad = [
                        cell(&cur, i - 1, k - 1),
                        cell(&cur, i - 1, k),
                        cell(&cur, i, k),
                        cell(&cur, i, k - 1),
                    ];
                    push_quad(&mut triangles, &positions, quad, a);
                }
            }
        }
        // Edges along x and z in slice j: the cells around are in layers j - 1 and j.
        if j >= 1 {
            for k in 0..nz {
                let (lo, hi) = union(&[spans_lower[k], spans_lower[(k + 1).min(nz - 1)]]);
                for i in lo.saturating_sub(1)..=hi.min(nx - 1) {
                    let a = in_lower[i + nx * k];
                    if i + 1 < nx && k >= 1 && k < nz - 1 && a != in_lower[i + 1 + nx * k] {
                        let quad = [
                            cell(&prev, i, k - 1),
                            cell(&cur, i, k - 1),
                            cell(&cur, i, k),
                            cell(&prev, i, k),
                        ];
                        push_quad(&mut triangles, &positions, quad, a);
                    }
                    if k + 1 < nz && i >= 1 && i < nx - 1 && a != in_lower[i + nx * (k + 1)] {
                        let quad = [
                            cell(&prev, i - 1, k),
                            cell(&prev, i, k),
                            cell(&cur, i, k),
                            cell(&cur, i - 1, k),
                        ];
                        push_quad(&mut triangles, &positions, quad, a);
                    }
                }
            }
        }
        std::mem::swap(&mut lower, &mut upper);
        std::mem::swap(&mut in_lower, &mut in_upper);
        std::mem::swap(&mut spans_lower, &mut spans_upper);
        std::mem::swap(&mut prev, &mut cur);
    }
    (positions, triangles)
}

/// The smallest range holding all of `spans` (each `(first, last)`, empty if `first > last`).
pub(crate) fn union(spans: &[(usize, usize)]) -> (usize, usize) {
    spans
        .iter()
        .fold((usize::MAX, 0), |(lo, hi), s| (lo.min(s.0), hi.max(s.1)))
}

/// Removes every ambiguous grid face (two diagonally opposite corners inside, the other two
/// outside) that has a corner in slice `upper`, by moving inside points of `upper` onto the
/// surface (value 0, which counts as outside).
///
/// With one vertex per cell, surface nets joins the two cells on either side of an
/// ambiguous face by one mesh edge that 4 quads use: a non-manifold edge. On this smooth
/// field such faces only appear where a saddle of the surface (a blend between two parts)
/// lies almost exactly in a grid plane, so all four corner values are within a rounding
/// error of zero and nudging one of them changes the shape by nothing visible. Only points
/// of `upper` change (the lower slice is final), and each change turns an inside point
/// outside, so the loop ends. `spans_*` are the inside spans per row (see [`surface_nets`]);
/// they stay valid (supersets) as points turn outside.
pub(crate) fn remove_ambiguous_faces(
    nx: usize,
    in_lower: &[bool],
    spans_lower: &[(usize, usize)],
    upper: &mut [f32],
    in_upper: &mut [bool],
    spans_upper: &[(usize, usize)],
) {
    let nz = in_lower.len() / nx;
    // The candidate that is least inside (closest to the surface) moves; ties: lowest index.
    let flip = |points: &[usize], upper: &mut [f32], in_upper: &mut [bool]| {
        let least_inside = points
            .iter()
            .copied()
            .filter(|&p| in_upper[p])
            .max_by(|&a, &b| upper[a].total_cmp(&upper[b]).then(b.cmp(&a)));
        if let Some(p) = least_inside {
            upper[p] = 0.0;
            in_upper[p] = false;
        }
    };
    let mut changed = true;
    while changed {
        changed = false;
        for k in 0..nz {
            let k1 = (k + 1).min(nz - 1);
            let (lo, hi) = union(&[
                spans_lower[k],
                spans_lower[k1],
                spans_upper[k],
                spans_upper[k1],
            ]);
            for i in lo.saturating_sub(1)..=hi.min(nx - 1) {
                let a = i + nx * k;
                let b = a + nx;
                // Vertical face with normal z: (i, k) and (i + 1, k) in both slices.
                if i + 1 < nx {
                    let (l0, l1, u0, u1) =
                        (in_lower[a], in_lower[a + 1], in_upper[a], in_upper[a + 1]);
                    if l0 == u1 && l1 == u0 && l0 != l1 {
                        flip(&[a, a + 1], upper, in_upper);
                        changed = true;
                    }
                }
                if k + 1 < nz {
                    // Vertical face with normal x: (i, k) and (i, k + 1) in both slices.
                    let (l0, l1, u0, u1) = (in_lower[a], in_lower[b], in_upper[a], in_upper[b]);
                    if l0 == u1 && l1 == u0 && l0 != l1 {
                        flip(&[a, b], upper, in_upper);
                        changed = true;
                    }
                    // Horizontal face in `upper`.
                    if i + 1 < nx {
                        let (u00, u10) = (in_upper[a], in_upper[a + 1]);
                        let (u01, u11) = (in_upper[b], in_upper[b + 1]);
                        if u00 == u11 && u10 == u01 && u00 != u10 {
                            flip(&[a, a + 1, b, b + 1], upper, in_upper);
                            changed = true;
                        }
                    }
                }
            }
        }
    }
}

/// Adds a quad as two triangles split along its shorter diagonal. `quad` is counter-clockwise
/// seen from the edge's positive end; `outward_positive` says that end is outside.
pub(crate) fn push_quad(
    tris: &mut Vec<[u32; 3]>,
    pos: &[Vec3],
    quad: [u32; 4],
    outward_positive: bool,
) {
    // The grid's boundary is outside (see `Body::new`), so every crossed edge is interior
    // and its 4 cells all have vertices.
    if quad.contains(&u32::MAX) {
        debug_assert!(false, "crossed edge on the grid boundary");
        return;
    }
    let [a, b, c, d] = if outward_positive {
        quad
    } else {
        [quad[3], quad[2], quad[1], quad[0]]
    };
    let p = |v: u32| pos[v as usize];
    if p(a).distance_squared(p(c)) <= p(b).distance_squared(p(d)) {
        tris.extend([[a, b, c], [a, c, d]]);
    } else {
        tris.extend([[a, b, d], [b, c, d]]);
    }
}

/// Moves each vertex onto the zero set by one Newton step (at most half a cell, so the
/// mesh cannot fold) and returns the unit normals: the field's gradient where the vertex
/// was, which a step that short leaves unchanged to well under a degree on this smooth field.
pub(crate) fn snap_to_surface(body: &Body, positions: &mut [Vec3]) -> Vec<Vec3> {
    let max_step = 0.5 * body.cell;
    let mut near = Vec::with_capacity(body.prims.len());
    positions
        .iter_mut()
        .map(|p| {
            body.parts_near(*p, &mut near);
            let g = body.gradient(&near, *p);
            let g2 = g.length_squared();
            if g2 > 1e-12 {
                let step = g * (body.eval(&near, *p) / g2);
                *p -= step.clamp_length_max(max_step);
            }
            g.try_normalize().unwrap_or(Vec3::Y)
        })
        .collect()
}
