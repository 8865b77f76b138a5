/*
 * libattitude fixed point: rotation vectors of every method and the
 * streaming/batch integrator (state machine over att_fx_integ).
 * Integer-only; formats and rounding as documented in attitude/fixed.h.
 */
#include "attitude/fixed.h"

#include "fixed_internal.h"
#include "fixed_prim.h"

/* acc[i] += (a × b)_i, exact (Q4.60 for Q2.30 inputs). */
static void fx_cross_acc(fx_acc acc[3], const int32_t a[3], const int32_t b[3])
{
    fx_mac(&acc[0], a[1], b[2]);
    fx_msc(&acc[0], a[2], b[1]);
    fx_mac(&acc[1], a[2], b[0]);
    fx_msc(&acc[1], a[0], b[2]);
    fx_mac(&acc[2], a[0], b[1]);
    fx_msc(&acc[2], a[1], b[0]);
}

/* out = round(k · x) per component, Q2.30 × Q2.30 → Q2.30 (|k| < 1). */
static void fx_scale3(int32_t k, const int32_t x[3], int32_t out[3])
{
    out[0] = fx_mul(k, x[0], 30);
    out[1] = fx_mul(k, x[1], 30);
    out[2] = fx_mul(k, x[2], 30);
}

/*
 * rv2:            Φ = Δθ1 + Δθ2 + (2/3 Δθ1) × Δθ2
 * rv3-reuse, n=2: Φ = Δθ2 + (1/12 Δθ1) × Δθ2
 * rv3-reuse, n=3: Φ = Δθ3 + (1/720 Δθ1) × Δθ2 + (−31/720 Δθ1) × Δθ3
 *                        + (121/720 Δθ2) × Δθ3
 * Scaled increments rounded to Q2.30; sums (×2^30) and cross products
 * accumulated exactly in Q4.60 and rounded once to Q2.30. With
 * |Δθ| ≤ 0.4: |Φ_i| ≤ 1.01 (rv2), 0.42 (reuse); no saturation possible.
 */
att_status att_fx_phi(att_fx_method method, const att_q30 *d, uint8_t n, att_q30 phi[3])
{
    fx_acc acc[3];
    int32_t t[3];
    uint8_t i;
    if (d == 0 || phi == 0) {
        return ATT_E_NULL;
    }
    switch (method) {
    case ATT_FX_RV1:
        if (n != 1u) {
            return ATT_E_ARG;
        }
        break;
    case ATT_FX_RV2:
        if (n != 2u) {
            return ATT_E_ARG;
        }
        break;
    case ATT_FX_RV3:
    case ATT_FX_RV3_CONING:
        if (n != 3u) {
            return ATT_E_ARG;
        }
        break;
    case ATT_FX_RV3_REUSE:
        if (n < 1u || n > 3u) {
            return ATT_E_ARG;
        }
        break;
    default:
        return (att_status)ATT_FX_E_METHOD;
    }
    if (!att_fx_dtheta_ok_(d, (uint8_t)(3u * n))) {
        return (att_status)ATT_FX_E_RANGE;
    }
    if (method == ATT_FX_RV3) {
        att_fx_phi_rv3_(d, ATT_FX_K_RV3_13, ATT_FX_K_RV3_23, phi);
        return ATT_OK;
    }
    if (method == ATT_FX_RV3_CONING) {
        att_fx_phi_rv3_(d, ATT_FX_K_RV3C_13, ATT_FX_K_RV3C_23, phi);
        return ATT_OK;
    }
    if (n == 1u) {
        phi[0] = d[0];
        phi[1] = d[1];
        phi[2] = d[2];
        return ATT_OK;
    }
    for (i = 0; i < 3; ++i) {
        fx_zero(&acc[i]);
        if (method == ATT_FX_RV2) {
            fx_add_shl(&acc[i], d[i] + d[3 + i], 30);
        } else {
            fx_add_shl(&acc[i], d[3u * (n - 1u) + i], 30);
        }
    }
    if (method == ATT_FX_RV2) {
        fx_scale3(ATT_FX_K_RV2, d, t);
        fx_cross_acc(acc, t, d + 3);
    } else if (n == 2u) {
        fx_scale3(ATT_FX_K_RV3R_START, d, t);
        fx_cross_acc(acc, t, d + 3);
    } else {
        fx_scale3(ATT_FX_K_RV3R_12, d, t);
        fx_cross_acc(acc, t, d + 3);
        fx_scale3(ATT_FX_K_RV3R_13, d, t);
        fx_cross_acc(acc, t, d + 6);
        fx_scale3(ATT_FX_K_RV3R_23, d + 3, t);
        fx_cross_acc(acc, t, d + 6);
    }
    for (i = 0; i < 3; ++i) {
        phi[i] = fx_round(&acc[i], 30);
    }
    return ATT_OK;
}

att_status att_fx_integ_init(att_fx_integ *s, att_fx_method method, const att_q30 q0[4])
{
    att_q30 q[4];
    att_status st;
    if (s == 0) {
        return ATT_E_NULL;
    }
    if ((int)method < (int)ATT_FX_RV1 || (int)method > (int)ATT_FX_RV3_REUSE) {
        return (att_status)ATT_FX_E_METHOD;
    }
    if (q0 == 0) {
        q[0] = ATT_FX_Q30_ONE;
        q[1] = 0;
        q[2] = 0;
        q[3] = 0;
    } else {
        st = att_fx_quat_normalize(q0, q);
        if (st != ATT_OK) {
            return st;
        }
    }
    s->q[0] = q[0];
    s->q[1] = q[1];
    s->q[2] = q[2];
    s->q[3] = q[3];
    s->method = (uint8_t)method;
    s->nbuf = 0;
    return ATT_OK;
}

static void fx_copy3(att_q30 *dst, const att_q30 *src)
{
    dst[0] = src[0];
    dst[1] = src[1];
    dst[2] = src[2];
}

int att_fx_integ_update(att_fx_integ *s, const att_q30 dtheta[3], att_q30 q_out[4])
{
    att_q30 d[9];
    att_q30 phi[3];
    att_status st;
    uint8_t n, need;
    if (s == 0 || dtheta == 0) {
        return ATT_E_NULL;
    }
    if (!att_fx_dtheta_ok_(dtheta, 3)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    switch (s->method) {
    case ATT_FX_RV1:
        need = 1;
        break;
    case ATT_FX_RV2:
        need = 2;
        break;
    case ATT_FX_RV3:
    case ATT_FX_RV3_CONING:
        need = 3;
        break;
    case ATT_FX_RV3_REUSE:
        need = 0; /* updates on every increment */
        break;
    default:
        return (att_status)ATT_FX_E_METHOD;
    }
    if (need != 0u && (uint8_t)(s->nbuf + 1u) < need) {
        fx_copy3(s->buf[s->nbuf], dtheta);
        s->nbuf++;
        return ATT_FX_PENDING;
    }
    n = (uint8_t)(s->nbuf + 1u);
    if (s->nbuf > 0u) {
        fx_copy3(d, s->buf[0]);
    }
    if (s->nbuf > 1u) {
        fx_copy3(d + 3, s->buf[1]);
    }
    fx_copy3(d + 3u * s->nbuf, dtheta);
    if (s->method == ATT_FX_RV3) {
        att_fx_phi_rv3_(d, ATT_FX_K_RV3_13, ATT_FX_K_RV3_23, phi);
    } else {
        st = att_fx_phi((att_fx_method)s->method, d, n, phi);
        if (st != ATT_OK) {
            return st;
        }
    }
    st = att_fx_apply_(s->q, phi);
    if (st != ATT_OK) {
        return st;
    }
    if (s->method == ATT_FX_RV3_REUSE) {
        if (s->nbuf < 2u) {
            fx_copy3(s->buf[s->nbuf], dtheta);
            s->nbuf++;
        } else {
            fx_copy3(s->buf[0], s->buf[1]);
            fx_copy3(s->buf[1], dtheta);
        }
    } else {
        s->nbuf = 0;
    }
    if (q_out != 0) {
        q_out[0] = s->q[0];
        q_out[1] = s->q[1];
        q_out[2] = s->q[2];
        q_out[3] = s->q[3];
    }
    return ATT_FX_UPDATED;
}

size_t att_fx_integ_outputs(const att_fx_integ *s, size_t n)
{
    if (s == 0) {
        return 0;
    }
    switch (s->method) {
    case ATT_FX_RV2:
        return (n + s->nbuf) / 2u;
    case ATT_FX_RV3:
    case ATT_FX_RV3_CONING:
        return (n + s->nbuf) / 3u;
    default:
        return n;
    }
}

att_status att_fx_integ_batch(att_fx_integ *s, const att_q30 *dtheta, size_t n,
                              att_q30 *q_out, size_t *n_out, size_t *err_index)
{
    size_t i, m = 0;
    int r;
    if (n_out != 0) {
        *n_out = 0;
    }
    if (s == 0 || (n > 0u && (dtheta == 0 || q_out == 0))) {
        return ATT_E_NULL;
    }
    for (i = 0; i < n; ++i) {
        if (!att_fx_dtheta_ok_(dtheta + 3u * i, 3)) {
            if (err_index != 0) {
                *err_index = i;
            }
            return (att_status)ATT_FX_E_RANGE;
        }
    }
    for (i = 0; i < n; ++i) {
        r = att_fx_integ_update(s, dtheta + 3u * i, q_out + 4u * m);
        if (r < 0) { /* not reachable: inputs checked above, state invariant kept */
            if (err_index != 0) {
                *err_index = i;
            }
            return (att_status)r;
        }
        if (r == ATT_FX_UPDATED) {
            ++m;
        }
    }
    if (n_out != 0) {
        *n_out = m;
    }
    return ATT_OK;
}
