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
 * energy it stores, so damping, sliding and rolling losses are all counted. */
#ifndef MC_CONTACT_LAW_H
#define MC_CONTACT_LAW_H

typedef struct {
  real3 normal;     /* unit normal from the other body to the ball */
  real overlap;     /* δ > 0, m */
  real3 v_rel;      /* ball's contact-point velocity minus the other's */
  real3 w_rel;      /* ω_ball − ω_other */
  real arm;         /* ball centre to contact point, m */
  real m_eff;       /* m* */
  real r_eff;       /* R* */
  real inv_inertia_sum; /* 1/I_ball + 1/I_other (the wall adds 0) */
} ContactGeom;

typedef struct {
  real3 force;      /* on the ball, N */
  real3 torque;     /* on the ball about its centre, N·m */
  real3 spring;     /* updated tangential spring ξ, m */
  real3 rolling;    /* the rolling-resistance couple, part of torque */
  real normal_force; /* Fn ≥ 0, N */
  real dissipated;  /* energy lost in this contact this step, J */
  real elastic;     /* energy stored in the contact now, J */
} ContactOut;

/* Hertz: 4/3·E*·sqrt(R*)·δ^1.5 = 2/3·Sn·δ with Sn = 2E*·sqrt(R*δ). */
MC_FN real hertz_normal_stiffness(real e_star, real r_eff, real overlap) {
  return R(2.0) * e_star * sqrt(r_eff * overlap);
}

MC_FN ContactOut contact_force(PairParams pp, ContactGeom g, real3 spring_old,
                               real dt, int law) {
  ContactOut out;
  const real3 n = g.normal;
  const real d = g.overlap;
  const real vn = dot(g.v_rel, n);
  const real3 vt = g.v_rel - vn * n;

  real f_elastic, kn_damp, kt, u_normal;
  if (law == MC_LAW_HERTZ) {
    const real sn = hertz_normal_stiffness(pp.e_star, g.r_eff, d);
    f_elastic = R(2.0) / R(3.0) * sn * d;
    kn_damp = sn;
    kt = R(8.0) * pp.g_star * sqrt(g.r_eff * d);
    u_normal = R(0.4) * f_elastic * d;
  } else {
    f_elastic = pp.kn * d;
    kn_damp = pp.kn;
    kt = pp.kt_over_kn * pp.kn;
    u_normal = R(0.5) * pp.kn * d * d;
  }
  /* The Hertz form carries sqrt(5/6)·sqrt(3/2) inside `damping` (see
   * restitution.cpp); both laws then read γ = damping·sqrt(S·m*). */
  const real gamma_n = pp.damping * sqrt(kn_damp * g.m_eff);
  const real gamma_t = pp.damping * sqrt(kt * g.m_eff);

  real fn = f_elastic - gamma_n * vn;
  if (fn < R(0.0)) fn = R(0.0);
  real dissipated = (f_elastic - fn) * vn * dt;

  /* Tangential spring: rotate the old spring into the new tangent plane. */
  real3 s = spring_old - dot(spring_old, n) * n;
  const real old_len2 = dot(spring_old, spring_old);
  const real new_len2 = dot(s, s);
  if (new_len2 > R(0.0)) s = s * sqrt(old_len2 / new_len2);
  const real u_t_old = R(0.5) * kt * dot(s, s);
  const real3 s_rot = s;
  s += vt * dt;
  real3 ft = -kt * s - gamma_t * vt;
  const real ft_len = length(ft);
  const real ft_max = pp.mu_slide * fn;
  if (ft_len > ft_max) {
    /* Sliding: the force is the Coulomb force, and the spring alone is set to
     * carry it. (Setting spring + dashpot to it, as LAMMPS' history model
     * does, loads the spring with the dashpot's force: at a fast slip it then
     * stores energy that no physical spring holds, and that energy vanishes
     * uncounted when the contact opens.) As Fn → 0 at separation the spring
     * goes to zero, so an opening contact takes no energy with it. */
    ft = (ft_len > R(0.0)) ? ft * (ft_max / ft_len) : ft;
    s = (kt > R(0.0)) ? (-R(1.0) / kt) * ft : make_real3(0, 0, 0);
  }
  const real u_t_new = R(0.5) * kt * dot(s, s);
  /* Work on the contact over the step minus the change of stored energy. The
   * spring's work is taken at the step's midpoint spring force: with the end
   * force a sticking spring would show ½·kt·|vt·dt|² of dissipation every
   * step that no contact loses. */
  const real3 slip = vt * dt;
  dissipated += -dot(ft, slip) - R(0.5) * kt * dot(s - s_rot, slip) - (u_t_new - u_t_old);

  /* Rolling resistance on the rolling part of the relative spin. */
  real3 w_roll = g.w_rel - dot(g.w_rel, n) * n;
  const real w_len = length(w_roll);
  real3 m_roll = make_real3(0, 0, 0);
  if (w_len > R(0.0) && pp.mu_roll > R(0.0)) {
    real m_mag = pp.mu_roll * g.r_eff * fn;
    const real cap = w_len / (dt * g.inv_inertia_sum);
    if (m_mag > cap) m_mag = cap;
    m_roll = (-m_mag / w_len) * w_roll;
    dissipated += m_mag * w_len * dt;
  }

  out.force = fn * n + ft;
  out.torque = cross(-g.arm * n, ft) + m_roll;
  out.spring = s;
  out.rolling = m_roll;
  out.normal_force = fn;
  out.dissipated = dissipated;
  out.elastic = u_normal + u_t_new;
  return out;
}

#endif /* MC_CONTACT_LAW_H */
