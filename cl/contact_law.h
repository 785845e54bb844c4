/* contact_law.h — the force of one contact, as a stateless function that the
 * kernels and the CPU reference both call.
 *
 * Normal: linear spring–dashpot (Cundall & Strack 1979) or Hertz with
 * Tsuji-type damping γ ∝ sqrt(S·m*) (the form of LIGGGHTS/EDEM, DESIGN.md).
 * No attraction: the normal force is clipped at zero, and the damping
 * coefficient is calibrated for that (restitution.cpp), so the rebound
 * velocity ratio equals the input e.
 * Tangential: incremental spring ξ with dashpot and Coulomb limit (Mindlin
 * no-slip stiffness for Hertz, kt = ratio·kn for linear); ξ is projected onto
 * the current tangent plane each step keeping its length, and truncated when
 * sliding so that the spring alone carries the Coulomb force.
 * Rolling: constant directional torque (Ai et al. 2011, model A),
 * M = −μr·R*·Fn·ω̂_roll, capped so one step cannot reverse the relative spin.
 * Energy: dissipation is the work done on the contact minus the change of the
 * energy it stores, so damping, sliding and rolling losses are all counted.
 * The books close with the solver's kinetic energy (velocities synchronised
 * to the step) only if two things are taken as the integrator sees them:
 * the stored tangential energy of the previous step with the stiffness it
 * had then (Hertz's kt follows the overlap; with this step's kt the losses
 * came out 12 % above the torque power in a turning drum), and the normal
 * dashpot's work at the synchronised relative speed (with the half-step-old
 * one, about ζ·ω·dt too high: 2 % at 25 steps a contact). The losses are
 * kept apart (normal, tangential, rolling) for the collision spectra.
 *
 * Written on plain structs of three reals (v3) and with selects instead of
 * branches, so that a kernel running one contact per work-item can be put in
 * SIMD lanes by PoCL: a float3 value or a branch between vectors stops its
 * work-group vectoriser (forces_grouped in forces.cl runs the law so). */
#ifndef MC_CONTACT_LAW_H
#define MC_CONTACT_LAW_H

typedef struct { real x, y, z; } v3;

MC_FN v3 v3_make(real x, real y, real z) { v3 r; r.x = x; r.y = y; r.z = z; return r; }
MC_FN v3 v3_add(v3 a, v3 b) { return v3_make(a.x + b.x, a.y + b.y, a.z + b.z); }
MC_FN v3 v3_sub(v3 a, v3 b) { return v3_make(a.x - b.x, a.y - b.y, a.z - b.z); }
MC_FN v3 v3_scale(real s, v3 a) { return v3_make(s * a.x, s * a.y, s * a.z); }
MC_FN real v3_dot(v3 a, v3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
MC_FN v3 v3_cross(v3 a, v3 b) {
  return v3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
/* c ? a : b, a component at a time */
MC_FN v3 v3_select(int c, v3 a, v3 b) {
  return v3_make(c ? a.x : b.x, c ? a.y : b.y, c ? a.z : b.z);
}
MC_FN v3 v3_of(real3 a) { return v3_make(a.x, a.y, a.z); }
MC_FN real3 real3_of(v3 a) { return make_real3(a.x, a.y, a.z); }

typedef struct {
  v3 normal;        /* unit normal from the other body to the ball */
  real overlap;     /* δ > 0, m */
  v3 v_rel;         /* ball's contact-point velocity minus the other's */
  v3 w_rel;         /* ω_ball − ω_other */
  real arm;         /* ball centre to contact point, m */
  real m_eff;       /* m* */
  real r_eff;       /* R* */
  real inv_inertia_sum; /* 1/I_ball + 1/I_other (the wall adds 0) */
} ContactGeom;

typedef struct {
  v3 force;         /* on the ball, N */
  v3 torque;        /* on the ball about its centre, N·m */
  v3 spring;        /* updated tangential spring ξ, m */
  v3 rolling;       /* the rolling-resistance couple, part of torque */
  real normal_force; /* Fn ≥ 0, N */
  real dissipated;  /* energy lost in this contact this step, J: */
  real loss_normal;     /*   in the normal dashpot (and the clip at Fn = 0) */
  real loss_tangential; /*   in the tangential dashpot and sliding */
  real loss_rolling;    /*   in rolling resistance */
  real slide;       /* sliding distance this step (0 while sticking), m */
  real elastic;     /* energy stored in the contact now, J */
} ContactOut;

/* Hertz: 4/3·E*·sqrt(R*)·δ^1.5 = 2/3·Sn·δ with Sn = 2E*·sqrt(R*δ). */
MC_FN real hertz_normal_stiffness(real e_star, real r_eff, real overlap) {
  return R(2.0) * e_star * sqrt(r_eff * overlap);
}

MC_FN ContactOut contact_force(PairParams pp, ContactGeom g, v3 spring_old,
                               real dt, int law) {
  ContactOut out;
  const v3 n = g.normal;
  const real d = g.overlap;
  const real vn = v3_dot(g.v_rel, n);
  const v3 vt = v3_sub(g.v_rel, v3_scale(vn, n));

  /* Both laws as selects (the Hertz root is taken either way). */
  const int hertz = law == MC_LAW_HERTZ;
  const real root = sqrt(fmax(g.r_eff * d, R(0.0)));
  const real sn = R(2.0) * pp.e_star * root;
  const real f_elastic = hertz ? R(2.0) / R(3.0) * sn * d : pp.kn * d;
  const real kn_damp = hertz ? sn : pp.kn;
  const real kt = hertz ? R(8.0) * pp.g_star * root : pp.kt_over_kn * pp.kn;
  const real u_normal = hertz ? R(0.4) * f_elastic * d : R(0.5) * pp.kn * d * d;
  /* The Hertz form carries sqrt(5/6)·sqrt(3/2) inside `damping` (see
   * restitution.cpp); both laws then read γ = damping·sqrt(S·m*). */
  const real gamma_n = pp.damping * sqrt(kn_damp * g.m_eff);
  const real gamma_t = pp.damping * sqrt(kt * g.m_eff);

  const real fn = fmax(f_elastic - gamma_n * vn, R(0.0));
  /* The dashpot's work at the relative speed synchronised to the step,
   * vn + ½·dt·Fn/m* (the contact's own push), as the kinetic energy is. */
  const real vn_sync = vn + R(0.5) * dt * fn / g.m_eff;
  const real loss_normal = (f_elastic - fn) * vn_sync * dt;

  /* Tangential spring: rotate the old spring into the new tangent plane,
   * keeping its length. */
  const v3 s_proj = v3_sub(spring_old, v3_scale(v3_dot(spring_old, n), n));
  const real old_len2 = v3_dot(spring_old, spring_old);
  const real new_len2 = v3_dot(s_proj, s_proj);
  const v3 s_rot = v3_scale(new_len2 > R(0.0) ? sqrt(old_len2 / new_len2) : R(1.0), s_proj);
  /* Hertz's kt follows the overlap: the old spring's energy is taken with
   * the stiffness it had, at the overlap of the previous step, δ + vn·dt. */
  const real kt_old = hertz ? R(8.0) * pp.g_star * sqrt(fmax(g.r_eff * (d + vn * dt), R(0.0))) : kt;
  const real u_t_old = R(0.5) * kt_old * v3_dot(s_rot, s_rot);
  const v3 slip = v3_scale(dt, vt);
  const v3 s_stick = v3_add(s_rot, slip);
  const v3 ft_stick = v3_sub(v3_scale(-kt, s_stick), v3_scale(gamma_t, vt));
  const real ft_len = sqrt(v3_dot(ft_stick, ft_stick));
  const real ft_max = pp.mu_slide * fn;
  /* Sliding: the force is the Coulomb force, and the spring alone is set to
   * carry it. (Setting spring + dashpot to it, as LAMMPS' history model
   * does, loads the spring with the dashpot's force: at a fast slip it then
   * stores energy that no physical spring holds, and that energy vanishes
   * uncounted when the contact opens.) As Fn → 0 at separation the spring
   * goes to zero, so an opening contact takes no energy with it. */
  const int sliding = ft_len > ft_max;
  const v3 ft = v3_scale(sliding ? ft_max / ft_len : R(1.0), ft_stick);
  const v3 s = v3_select(sliding, v3_scale(kt > R(0.0) ? -R(1.0) / kt : R(0.0), ft), s_stick);
  const real u_t_new = R(0.5) * kt * v3_dot(s, s);
  /* Work on the contact over the step minus the change of stored energy. The
   * spring's work is taken at the step's midpoint spring force, the mean of
   * the old spring's force (at its own stiffness) and the new one's: with the
   * end force a sticking spring would show ½·kt·|vt·dt|² of dissipation every
   * step that no contact loses. */
  const real loss_tangential = -v3_dot(ft, slip) -
                               R(0.5) * v3_dot(v3_sub(v3_scale(kt, s), v3_scale(kt_old, s_rot)), slip) -
                               (u_t_new - u_t_old);

  /* Rolling resistance on the rolling part of the relative spin. */
  const v3 w_roll = v3_sub(g.w_rel, v3_scale(v3_dot(g.w_rel, n), n));
  const real w_len = sqrt(v3_dot(w_roll, w_roll));
  const int rolling = w_len > R(0.0) && pp.mu_roll > R(0.0);
  const real cap = w_len / (dt * g.inv_inertia_sum);
  const real m_mag = rolling ? fmin(pp.mu_roll * g.r_eff * fn, cap) : R(0.0);
  const v3 m_roll = v3_scale(rolling ? -m_mag / w_len : R(0.0), w_roll);
  /* Its work at the relative spin synchronised to the step, as above. */
  const real loss_rolling = m_mag * (w_len - R(0.5) * dt * m_mag * g.inv_inertia_sum) * dt;

  out.force = v3_add(v3_scale(fn, n), ft);
  out.torque = v3_add(v3_cross(v3_scale(-g.arm, n), ft), m_roll);
  out.spring = s;
  out.rolling = m_roll;
  out.normal_force = fn;
  out.loss_normal = loss_normal;
  out.loss_tangential = loss_tangential;
  out.loss_rolling = loss_rolling;
  out.dissipated = loss_normal + loss_tangential + loss_rolling;
  out.slide = sliding ? dt * sqrt(v3_dot(vt, vt)) : R(0.0);
  out.elastic = u_normal + u_t_new;
  return out;
}

#endif /* MC_CONTACT_LAW_H */
