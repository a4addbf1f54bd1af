//! The iterations behind [`super::IkSolveJob::run`]. Every buffer comes from
//! [`IkScratch`], sized by [`IkScratch::new`]; nothing here allocates. Indices come from
//! the compiled [`IkProblem`] and buffers sized from it (checked by `validate()`).

use glam::{Affine3A, DVec3, Mat3, Quat, Vec3};
use rigport_model::Transform;

use super::linalg::{best_rotation, cholesky_solve, dot, pinv_solve};
use super::{axis_angle, ADAPTIVE_BIAS, ADAPTIVE_GAIN, MAX_SUBSTEPS};
use super::{IkHandle, IkMethod, IkProblem, IkReport, IkScratch, IkSettings, Lambda};

/// Below this length a direction is undefined (lever arms, FABRIK bones): in the asset's
/// unit, relative to nothing, so it only guards divisions by zero.
const TINY: f32 = 1e-12;

/// Forward kinematics of the joints the problem needs (`model` has one entry per joint;
/// others are left as they are).
pub(super) fn forward(problem: &IkProblem, pose: &[Transform], model: &mut [Affine3A]) {
    for &j in &problem.fk_joints {
        let j = j as usize;
        let local = local_affine(&pose[j]);
        model[j] = match problem.parents[j] {
            Some(p) => model[p.get()] * local,
            None => local,
        };
    }
}

/// `T · R · S` of a local transform, as an affine map (cheaper than `Mat4` products).
#[inline]
fn local_affine(t: &Transform) -> Affine3A {
    // Unit scale is the common case (every importer's rest poses): skip the multiply.
    if t.scale == Vec3::ONE {
        Affine3A::from_rotation_translation(t.rotation, t.translation)
    } else {
        Affine3A::from_scale_rotation_translation(t.scale, t.rotation, t.translation)
    }
}

/// The origin of a model transform.
#[inline]
fn origin(m: &Affine3A) -> Vec3 {
    Vec3::from(m.translation)
}

/// The linear part of a model transform.
#[inline]
fn linear(m: &Affine3A) -> Mat3 {
    Mat3::from(m.matrix3)
}

/// The rotation of a model matrix's linear part (columns normalized: exact for rotation times
/// scale).
fn rotation_of(m: &Mat3) -> Quat {
    let m = Mat3::from_cols(
        m.x_axis.normalize_or_zero(),
        m.y_axis.normalize_or_zero(),
        m.z_axis.normalize_or_zero(),
    );
    let q = Quat::from_mat3(&m);
    if q.is_finite() && q.length_squared() > 0.5 {
        q.normalize()
    } else {
        Quat::IDENTITY
    }
}

/// The linear part of joint `j`'s parent model matrix (identity above a root).
fn parent_linear(problem: &IkProblem, model: &[Affine3A], j: usize) -> Mat3 {
    problem.parents[j].map_or(Mat3::IDENTITY, |p| linear(&model[p.get()]))
}

/// `A⁻¹`, or the identity when `A` is singular (a zero-scaled parent: nothing below it moves
/// anyway).
fn inverse_or_identity(a: &Mat3) -> Mat3 {
    // glam's inverse divides by the determinant: a singular matrix gives inf or NaN.
    let inv = a.inverse();
    if inv.is_finite() {
        inv
    } else {
        Mat3::IDENTITY
    }
}

/// The rotation vector of `goal · current⁻¹` (shortest way round), radians.
fn rotation_error(goal: Quat, current: Quat) -> Vec3 {
    let (axis, angle) = axis_angle(goal * current.conjugate());
    let v = axis * angle;
    if v.is_finite() {
        v
    } else {
        Vec3::ZERO
    }
}

/// Angle between two rotations, radians in `0..=π`.
fn angle_between(a: Quat, b: Quat) -> f32 {
    axis_angle(a * b.conjugate()).1
}

/// Recomputes model matrices, effector positions and (for handles with an orientation
/// target) handle rotations.
pub(super) fn update_effectors(
    problem: &IkProblem,
    targets: &[IkHandle],
    pose: &[Transform],
    s: &mut IkScratch,
) {
    forward(problem, pose, &mut s.model);
    s.unit_scale = problem
        .fk_joints
        .iter()
        .all(|&j| pose[j as usize].scale == Vec3::ONE);
    for ((h, e), t) in problem.effectors.iter().enumerate().zip(targets) {
        let m = &s.model[e.joint.get()];
        s.eff[h] = m.transform_point3(e.local_offset);
        if t.orientation.is_some() {
            s.eff_rot[h] = rotation_of(&linear(m));
        }
    }
}

/// Weighted squared error against the current goals, and whether all handles are within
/// tolerance.
fn measure(
    problem: &IkProblem,
    targets: &[IkHandle],
    settings: &IkSettings,
    s: &IkScratch,
) -> (f64, bool) {
    let l = f64::from(problem.length_scale);
    let mut err = 0.0_f64;
    let mut converged = true;
    for (h, t) in targets.iter().enumerate() {
        if t.weight <= 0.0 {
            continue;
        }
        let dist = s.goal[h].distance(s.eff[h]);
        let angle = s.goal_rot[h].map_or(0.0, |g| angle_between(g, s.eff_rot[h]));
        err += f64::from(t.weight) * (f64::from(dist).powi(2) + (l * f64::from(angle)).powi(2));
        converged &= dist <= settings.tolerance && angle <= settings.orientation_tolerance_rad;
    }
    (err, converged)
}

/// The whole solve: sub-steps, each an iteration loop; final residuals into `report`.
pub(super) fn solve(
    problem: &IkProblem,
    targets: &[IkHandle],
    settings: &IkSettings,
    pose: &mut [Transform],
    s: &mut IkScratch,
    report: &mut IkReport,
) {
    update_effectors(problem, targets, pose, s);
    s.start.copy_from_slice(&s.eff);
    s.start_rot.copy_from_slice(&s.eff_rot);
    let portions = match settings.substep {
        Some(step) => {
            let far = targets
                .iter()
                .zip(&s.start)
                .filter(|(t, _)| t.weight > 0.0)
                .map(|(t, e)| t.target.distance(*e))
                .fold(0.0_f32, f32::max);
            // Finite by validation; `as` saturates, and the clamp bounds the work.
            ((far / step).ceil() as u32).clamp(1, MAX_SUBSTEPS)
        }
        None => 1,
    };
    report.iterations = 0;
    report.substeps = portions;
    for k in 1..=portions {
        let f = k as f32 / portions as f32;
        let last = k == portions;
        for (h, t) in targets.iter().enumerate() {
            s.goal[h] = if last {
                t.target
            } else {
                s.start[h].lerp(t.target, f)
            };
            s.goal_rot[h] = t.orientation.map(|q| {
                let q = q.normalize();
                if last {
                    q
                } else {
                    s.start_rot[h].slerp(q, f).normalize()
                }
            });
        }
        report.iterations += solve_portion(problem, targets, settings, pose, s);
    }
    let (_, converged) = measure(problem, targets, settings, s);
    report.converged = converged;
    for (h, t) in targets.iter().enumerate() {
        report.residuals[h] = t.target.distance(s.eff[h]);
        report.orientation_residuals_rad[h] = t
            .orientation
            .map_or(0.0, |q| angle_between(q.normalize(), s.eff_rot[h]));
    }
}

/// Iterates towards `s.goal` from the current pose (`s.model` and `s.eff` current on entry,
/// and on exit); returns the iterations run. Leaves the best pose seen in `pose`.
fn solve_portion(
    problem: &IkProblem,
    targets: &[IkHandle],
    settings: &IkSettings,
    pose: &mut [Transform],
    s: &mut IkScratch,
) -> u32 {
    let mut best = f64::INFINITY;
    let mut last;
    let mut iterations = 0;
    let mut current = true;
    loop {
        if !current {
            update_effectors(problem, targets, pose, s);
        }
        current = false;
        let (err, converged) = measure(problem, targets, settings, s);
        last = if err.is_finite() { err } else { f64::INFINITY };
        if last < best {
            best = last;
            s.best_pose.copy_from_slice(pose);
        }
        if converged || iterations >= settings.max_iterations {
            break;
        }
        let moved = match settings.method {
            IkMethod::Ccd => ccd_sweep(problem, targets, settings, pose, s),
            IkMethod::Fabrik => fabrik_pass(problem, targets, settings, pose, s),
            _ => jacobian_step(problem, targets, settings, pose, s),
        };
        if !moved {
            break;
        }
        iterations += 1;
    }
    if last > best {
        pose.copy_from_slice(&s.best_pose);
        update_effectors(problem, targets, pose, s);
    }
    iterations
}

/// Projects a joint's new local rotation into its limit (if any).
fn limited(problem: &IkProblem, slot: usize, joint: usize, q: Quat) -> Quat {
    match problem.limits[slot] {
        Some(limit) => {
            let rest = problem.rest_rotation[joint];
            (rest * limit.project(rest.conjugate() * q)).normalize()
        }
        None => q,
    }
}

/// Fills the Jacobian and `s.err` for the current pose (`s.model`, `s.eff`, `s.eff_rot`
/// current) and goals, rows scaled by `√weight`; returns `(rows, cols)`.
///
/// Row layout: per handle of non-zero weight, 3 position rows, then 3 orientation rows if
/// it has a goal orientation (`s.row_start`). Column blocks of 3: one per slot, then one
/// per root when roots translate. The Jacobian is stored by block: `s.slab[block ·
/// max_rows + row]` holds the row's 3 entries in that block, written only for the rows of
/// the block's handles ([`IkProblem`]'s `block_handles`); every other entry is zero and
/// never read. [`densify`] writes the dense row-major matrix when a method needs it.
pub(super) fn build_jacobian(
    problem: &IkProblem,
    targets: &[IkHandle],
    settings: &IkSettings,
    s: &mut IkScratch,
) -> (usize, usize) {
    let slots = problem.movable.len();
    let l = problem.length_scale;
    let mut rows = 0usize;
    for (h, t) in targets.iter().enumerate() {
        s.row_start[h] = rows as u32;
        if t.weight > 0.0 {
            rows += if s.goal_rot[h].is_some() { 6 } else { 3 };
        }
    }
    s.row_start[targets.len()] = rows as u32;
    let cols = 3 * slots
        + if settings.free_root_translation {
            3 * problem.roots.len()
        } else {
            0
        };
    if rows == 0 || cols == 0 {
        return (rows, cols);
    }
    for (si, &j) in problem.movable.iter().enumerate() {
        let a = parent_linear(problem, &s.model, j as usize);
        // With unit scales every model matrix is a rotation: its inverse is its transpose.
        s.parent_inv[si] = if s.unit_scale {
            a.transpose()
        } else {
            inverse_or_identity(&a)
        };
        s.parent_lin[si] = a;
    }
    let max_rows = problem.max_rows();
    for (h, t) in targets.iter().enumerate() {
        if t.weight <= 0.0 {
            continue;
        }
        let sw = t.weight.sqrt();
        let r0 = s.row_start[h] as usize;
        let e = (s.goal[h] - s.eff[h]) * sw;
        s.err[r0] = f64::from(e.x);
        s.err[r0 + 1] = f64::from(e.y);
        s.err[r0 + 2] = f64::from(e.z);
        let orient = s.goal_rot[h].map(|g| rotation_error(g, s.eff_rot[h]) * (l * sw));
        if let Some(o) = orient {
            s.err[r0 + 3] = f64::from(o.x);
            s.err[r0 + 4] = f64::from(o.y);
            s.err[r0 + 5] = f64::from(o.z);
        }
        for &slot in problem.handle_slots.row(h) {
            let slot = slot as usize;
            let j = problem.movable[slot] as usize;
            let (a, inv) = (&s.parent_lin[slot], &s.parent_inv[slot]);
            let u = *inv * (s.eff[h] - origin(&s.model[j]));
            // Column k is A (e_k × u); row i of the block is (col_x[i], col_y[i], col_z[i]).
            let cx = *a * Vec3::new(0.0, -u.z, u.y) * sw;
            let cy = *a * Vec3::new(u.z, 0.0, -u.x) * sw;
            let cz = *a * Vec3::new(-u.y, u.x, 0.0) * sw;
            let base = slot * max_rows + r0;
            s.slab[base] = DVec3::new(cx.x.into(), cy.x.into(), cz.x.into());
            s.slab[base + 1] = DVec3::new(cx.y.into(), cy.y.into(), cz.y.into());
            s.slab[base + 2] = DVec3::new(cx.z.into(), cy.z.into(), cz.z.into());
            if orient.is_some() {
                let scale = l * sw;
                let wx = a.x_axis.normalize_or_zero() * scale;
                let wy = a.y_axis.normalize_or_zero() * scale;
                let wz = a.z_axis.normalize_or_zero() * scale;
                s.slab[base + 3] = DVec3::new(wx.x.into(), wy.x.into(), wz.x.into());
                s.slab[base + 4] = DVec3::new(wx.y.into(), wy.y.into(), wz.y.into());
                s.slab[base + 5] = DVec3::new(wx.z.into(), wy.z.into(), wz.z.into());
            }
        }
        if settings.free_root_translation {
            let base = (slots + problem.handle_root[h] as usize) * max_rows + r0;
            let sw = f64::from(sw);
            s.slab[base] = DVec3::new(sw, 0.0, 0.0);
            s.slab[base + 1] = DVec3::new(0.0, sw, 0.0);
            s.slab[base + 2] = DVec3::new(0.0, 0.0, sw);
            if orient.is_some() {
                s.slab[base + 3..base + 6].fill(DVec3::ZERO);
            }
        }
    }
    (rows, cols)
}

/// The rows of column block `block`, ascending: the rows of its handles.
fn block_rows<'a>(
    problem: &'a IkProblem,
    row_start: &'a [u32],
    block: usize,
) -> impl Iterator<Item = usize> + Clone + 'a {
    problem
        .block_handles
        .row(block)
        .iter()
        .flat_map(move |&h| row_start[h as usize] as usize..row_start[h as usize + 1] as usize)
}

/// Writes the dense row-major `rows x cols` Jacobian into `s.jac` from the blocks.
pub(super) fn densify(problem: &IkProblem, s: &mut IkScratch, rows: usize, cols: usize) {
    let max_rows = problem.max_rows();
    let jac = &mut s.jac[..rows * cols];
    jac.fill(0.0);
    for block in 0..cols / 3 {
        for r in block_rows(problem, &s.row_start, block) {
            let v = s.slab[block * max_rows + r];
            jac[r * cols + 3 * block..r * cols + 3 * block + 3].copy_from_slice(&v.to_array());
        }
    }
}

/// One Jacobian step (DLS, pseudo-inverse or transpose). Returns whether the pose changed.
fn jacobian_step(
    problem: &IkProblem,
    targets: &[IkHandle],
    settings: &IkSettings,
    pose: &mut [Transform],
    s: &mut IkScratch,
) -> bool {
    let (rows, cols) = build_jacobian(problem, targets, settings, s);
    if rows == 0 || cols == 0 {
        return false;
    }
    let l = problem.length_scale;
    let max_rows = problem.max_rows();
    match settings.method {
        IkMethod::Dls { lambda } => {
            let err = &s.err[..rows];
            let lambda2 = match lambda {
                Lambda::Fixed(x) => f64::from(x) * f64::from(x),
                Lambda::Adaptive => {
                    f64::from(ADAPTIVE_GAIN) * err.iter().map(|v| v * v).sum::<f64>()
                        + f64::from(ADAPTIVE_BIAS) * f64::from(l) * f64::from(l)
                }
            };
            if rows <= cols {
                // (J Jᵀ + λ² I) y = e, Δθ = Jᵀ y, block by block: a block contributes
                // only to the rows of its own handles.
                let sys = &mut s.sys[..rows * rows];
                sys.fill(0.0);
                let blocks = cols / 3;
                for group in 0..problem.block_groups.start.len().saturating_sub(1) {
                    // The group's blocks all have the rows of the same handles: gather
                    // those rows' entries row-major (width 3 per block), then one tight
                    // lower-triangle pass of dot products.
                    let members = problem.block_groups.row(group);
                    let members = &members[..members.partition_point(|&b| (b as usize) < blocks)];
                    let Some(&first) = members.first() else {
                        continue;
                    };
                    let width = 3 * members.len();
                    let mut n = 0;
                    for r in block_rows(problem, &s.row_start, first as usize) {
                        s.gather_rows[n] = r as u32;
                        let dst = &mut s.gather[n * width..(n + 1) * width];
                        for (d, &b) in dst.chunks_exact_mut(3).zip(members) {
                            d.copy_from_slice(&s.slab[b as usize * max_rows + r].to_array());
                        }
                        n += 1;
                    }
                    let (idx, val) = (&s.gather_rows[..n], &s.gather[..n * width]);
                    for i in 0..n {
                        let ri = idx[i] as usize;
                        let vi = &val[i * width..(i + 1) * width];
                        let row = &mut sys[ri * rows..ri * rows + ri + 1];
                        for (j, &rj) in idx[..=i].iter().enumerate() {
                            let vj = &val[j * width..(j + 1) * width];
                            row[rj as usize] += dot(vi, vj);
                        }
                    }
                }
                for r in 0..rows {
                    sys[r * rows + r] += lambda2;
                }
                let y = &mut s.rhs[..rows];
                y.copy_from_slice(err);
                cholesky_solve(sys, rows, y);
                for block in 0..cols / 3 {
                    let slab = &s.slab[block * max_rows..(block + 1) * max_rows];
                    let d = block_rows(problem, &s.row_start, block)
                        .fold(DVec3::ZERO, |acc, r| acc + slab[r] * y[r]);
                    s.dtheta[3 * block..3 * block + 3].copy_from_slice(&d.to_array());
                }
            } else {
                // (Jᵀ J + λ² I) Δθ = Jᵀ e (more rows than columns: a few joints with
                // orientation targets).
                densify(problem, s, rows, cols);
                let (jac, err) = (&s.jac[..rows * cols], &s.err[..rows]);
                let sys = &mut s.sys[..cols * cols];
                let dtheta = &mut s.dtheta[..cols];
                sys.fill(0.0);
                dtheta.fill(0.0);
                for r in 0..rows {
                    let jr = &jac[r * cols..(r + 1) * cols];
                    for a in 0..cols {
                        if jr[a] == 0.0 {
                            continue;
                        }
                        for b in 0..=a {
                            sys[a * cols + b] += jr[a] * jr[b];
                        }
                        dtheta[a] += jr[a] * err[r];
                    }
                }
                for a in 0..cols {
                    sys[a * cols + a] += lambda2;
                }
                cholesky_solve(sys, cols, dtheta);
            }
        }
        IkMethod::Pinv { cutoff } => {
            densify(problem, s, rows, cols);
            pinv_solve(
                &mut s.jac[..rows * cols],
                (rows, cols),
                &s.err[..rows],
                f64::from(cutoff),
                &mut s.svd_work[..rows * rows + rows],
                &mut s.dtheta[..cols],
            );
        }
        _ => {
            // Transpose: Δθ = α Jᵀ e with α = ⟨e, J Jᵀ e⟩ / |J Jᵀ e|² (Buss 2004).
            densify(problem, s, rows, cols);
            let (jac, err) = (&s.jac[..rows * cols], &s.err[..rows]);
            let dtheta = &mut s.dtheta[..cols];
            dtheta.fill(0.0);
            for (r, er) in err.iter().enumerate() {
                for (d, j) in dtheta.iter_mut().zip(&jac[r * cols..(r + 1) * cols]) {
                    *d += j * er;
                }
            }
            let jjte = &mut s.tmp_rows[..rows];
            for (r, out) in jjte.iter_mut().enumerate() {
                *out = jac[r * cols..(r + 1) * cols]
                    .iter()
                    .zip(dtheta.iter())
                    .map(|(j, d)| j * d)
                    .sum();
            }
            let num: f64 = err.iter().zip(jjte.iter()).map(|(e, v)| e * v).sum();
            let den: f64 = jjte.iter().map(|v| v * v).sum();
            let alpha = if den > 0.0 { num / den } else { 0.0 };
            for d in dtheta.iter_mut() {
                *d *= alpha;
            }
        }
    }
    apply_step(problem, settings, pose, &s.dtheta[..cols])
}

/// Applies a Jacobian step, scaled as a whole so no joint turns more than
/// `max_step_rad` (and no root moves more than `max_step_rad · length_scale`).
fn apply_step(
    problem: &IkProblem,
    settings: &IkSettings,
    pose: &mut [Transform],
    dtheta: &[f64],
) -> bool {
    if dtheta.iter().any(|v| !v.is_finite()) {
        return false;
    }
    let max_step = f64::from(settings.max_step_rad);
    let l = f64::from(problem.length_scale);
    let slots = problem.movable.len();
    let mut largest = 0.0_f64;
    for (b, block) in dtheta.chunks_exact(3).enumerate() {
        let norm = (block[0] * block[0] + block[1] * block[1] + block[2] * block[2]).sqrt();
        largest = largest.max(if b < slots { norm } else { norm / l });
    }
    if largest <= 0.0 || largest.is_nan() {
        return false;
    }
    let scale = if largest > max_step {
        max_step / largest
    } else {
        1.0
    };
    let mut moved = false;
    for (b, block) in dtheta.chunks_exact(3).enumerate() {
        let v = Vec3::new(
            (block[0] * scale) as f32,
            (block[1] * scale) as f32,
            (block[2] * scale) as f32,
        );
        if v == Vec3::ZERO {
            continue;
        }
        moved = true;
        if b < slots {
            let j = problem.movable[b] as usize;
            let q = (Quat::from_scaled_axis(v) * pose[j].rotation).normalize();
            pose[j].rotation = limited(problem, b, j, q);
        } else if let Some(&root) = problem.roots.get(b - slots) {
            pose[root as usize].translation += v;
        }
    }
    moved
}

/// Turns movable joint `slot` by the model-space rotation `r` (its angle clamped to
/// `max_step_rad`, then the joint's limit applied); returns the model-space rotation
/// actually applied.
fn turn_joint(
    problem: &IkProblem,
    settings: &IkSettings,
    pose: &mut [Transform],
    model: &[Affine3A],
    slot: usize,
    r: Quat,
) -> Quat {
    let j = problem.movable[slot] as usize;
    let (axis, angle) = axis_angle(r);
    let angle = angle.min(settings.max_step_rad);
    if angle.is_nan() || angle <= 0.0 || !axis.is_finite() {
        return Quat::IDENTITY;
    }
    let a = parent_linear(problem, model, j);
    let inv = inverse_or_identity(&a);
    // Model-space axis to the parent frame: exact for rotation times uniform scale.
    let local_axis = (inv * axis).normalize_or_zero();
    if local_axis == Vec3::ZERO {
        return Quat::IDENTITY;
    }
    let old = pose[j].rotation;
    let new = (Quat::from_axis_angle(local_axis, angle) * old).normalize();
    let new = limited(problem, slot, j, new);
    pose[j].rotation = new;
    let delta = new * old.conjugate();
    let (local_axis, applied) = axis_angle(delta);
    let world_axis = (a * local_axis).normalize_or_zero();
    if world_axis == Vec3::ZERO || applied.is_nan() || applied <= 0.0 {
        Quat::IDENTITY
    } else {
        Quat::from_axis_angle(world_axis, applied)
    }
}

/// CCD and FABRIK meet orientation targets by setting the handle joint's rotation (when it
/// is movable). Returns whether a rotation changed.
fn set_orientations(
    problem: &IkProblem,
    targets: &[IkHandle],
    pose: &mut [Transform],
    s: &mut IkScratch,
) -> bool {
    if !s.goal_rot.iter().any(Option::is_some) {
        return false;
    }
    let mut changed = false;
    forward(problem, pose, &mut s.model);
    for (h, t) in targets.iter().enumerate() {
        let (Some(goal), true) = (s.goal_rot[h], t.weight > 0.0) else {
            continue;
        };
        let j = t.joint.get();
        let Some(slot) = problem.slot_of[j] else {
            continue;
        };
        let parent = rotation_of(&parent_linear(problem, &s.model, j));
        let q = limited(
            problem,
            slot as usize,
            j,
            (parent.conjugate() * goal).normalize(),
        );
        changed |= q != pose[j].rotation;
        pose[j].rotation = q;
    }
    changed
}

/// One CCD sweep, deepest joint first. `s.eff` is current on entry.
fn ccd_sweep(
    problem: &IkProblem,
    targets: &[IkHandle],
    settings: &IkSettings,
    pose: &mut [Transform],
    s: &mut IkScratch,
) -> bool {
    let mut moved = false;
    for slot in (0..problem.movable.len()).rev() {
        let handles = problem.slot_handles.row(slot);
        if handles.is_empty() {
            continue;
        }
        // The pivot depends only on ancestors, which come later in this sweep.
        let o = origin(&s.model[problem.movable[slot] as usize]);
        let r = best_rotation(handles.iter().map(|&h| {
            let h = h as usize;
            (s.eff[h] - o, s.goal[h] - o, targets[h].weight)
        }));
        let applied = turn_joint(problem, settings, pose, &s.model, slot, r);
        if applied != Quat::IDENTITY {
            moved = true;
            for &h in handles {
                let h = h as usize;
                s.eff[h] = o + applied * (s.eff[h] - o);
            }
        }
    }
    set_orientations(problem, targets, pose, s) | moved
}

/// One FABRIK iteration: backward and forward passes on the point tree, then joint
/// rotations recovered parents first. `s.model` and `s.eff` are current on entry.
fn fabrik_pass(
    problem: &IkProblem,
    targets: &[IkHandle],
    settings: &IkSettings,
    pose: &mut [Transform],
    s: &mut IkScratch,
) -> bool {
    let t = &problem.fabrik;
    let nodes = t.slot.len();
    let joint_of_node = |i: usize| t.slot[i].map(|sl| problem.movable[sl as usize] as usize);
    for i in 0..nodes {
        s.fab_p[i] = match (joint_of_node(i), t.handle[i]) {
            (Some(j), _) => origin(&s.model[j]),
            (None, Some(h)) => s.eff[h as usize],
            (None, None) => Vec3::ZERO,
        };
    }
    for i in 0..nodes {
        if let Some(q) = t.parent[i] {
            let q = q as usize;
            let pj = joint_of_node(q).unwrap_or(0);
            let lin = linear(&s.model[pj]);
            s.fab_len[i] = s.fab_p[i].distance(s.fab_p[q]);
            s.fab_off[i] = inverse_or_identity(&lin) * (s.fab_p[i] - s.fab_p[q]);
        }
    }
    // Backward: from the effectors towards the bases; a pivot with several children goes
    // to the weighted centroid of the positions its children ask for.
    s.fab_sum[..nodes].fill(Vec3::ZERO);
    s.fab_w[..nodes].fill(0.0);
    for i in (0..nodes).rev() {
        let (b, w) = match t.handle[i] {
            Some(h) => {
                let w = targets[h as usize].weight;
                let b = if w > 0.0 {
                    s.goal[h as usize]
                } else {
                    s.fab_p[i]
                };
                (b, w)
            }
            None if s.fab_w[i] > 0.0 => (s.fab_sum[i] / s.fab_w[i], s.fab_w[i]),
            None => (s.fab_p[i], 0.0),
        };
        s.fab_b[i] = b;
        s.fab_w[i] = w;
        if let Some(q) = t.parent[i] {
            let q = q as usize;
            let mut dir = s.fab_p[q] - b;
            if dir.length_squared() <= TINY {
                dir = s.fab_p[q] - s.fab_p[i];
            }
            let cand = b + dir.normalize_or_zero() * s.fab_len[i];
            s.fab_sum[q] += cand * w;
            s.fab_w[q] += w;
        }
    }
    // Forward: bases stay, every point goes back to its bone length from its parent.
    for i in 0..nodes {
        s.fab_f[i] = match t.parent[i] {
            Some(q) => {
                let q = q as usize;
                let mut dir = s.fab_b[i] - s.fab_f[q];
                if dir.length_squared() <= TINY {
                    dir = s.fab_p[i] - s.fab_p[q];
                }
                s.fab_f[q] + dir.normalize_or_zero() * s.fab_len[i]
            }
            None => s.fab_p[i],
        };
    }
    // Recovery: forward kinematics parents first; each pivot joint turns so its children's
    // directions best match the solved ones.
    let mut moved = false;
    for &j in &problem.fk_joints {
        let j = j as usize;
        let parent = problem.parents[j].map(|p| s.model[p.get()]);
        let local = local_affine(&pose[j]);
        s.model[j] = parent.map_or(local, |p| p * local);
        let Some(slot) = problem.slot_of[j] else {
            continue;
        };
        let Some(node) = t.node_of_slot[slot as usize] else {
            continue;
        };
        let node = node as usize;
        let children = t.children.row(node);
        if children.is_empty() {
            continue;
        }
        let lin = linear(&s.model[j]);
        let r = best_rotation(children.iter().map(|&c| {
            let c = c as usize;
            (lin * s.fab_off[c], s.fab_f[c] - s.fab_f[node], s.fab_w[c])
        }));
        let applied = turn_joint(problem, settings, pose, &s.model, slot as usize, r);
        if applied != Quat::IDENTITY {
            moved = true;
            let local = local_affine(&pose[j]);
            s.model[j] = parent.map_or(local, |p| p * local);
        }
    }
    set_orientations(problem, targets, pose, s) | moved
}
