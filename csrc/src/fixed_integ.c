/*
 * libattitude fixed point: rotation vectors of every method and the
 * streaming/batch integrator (state machine over att_fx_integ).
 * Integer-only; formats and rounding as documented in attitude/fixed.h.
 */
#include "attitude/fixed.h"

#include "fixed_internal.h"
#include "fixed_prim.h"

/*
 * Two-increment forms: Φ = s·(a + b) ... precisely
 *   rv2:            Φ = a + b + (2/3 a) × b
 *   reuse n=2:      Φ = b + (1/12 a) × b
 * k·a rounded to Q2.30; cross terms exact in Q4.60, rounded once; integer
 * sum added. |Φ_i| ≤ 0.8 + 2/3·2·0.16 < 1.1.
 */
static void fx_phi2(const att_q30 a[3], const att_q30 b[3], int32_t k, uint8_t with_a, uint32_t t,
                    att_q30 phi[3])
{
    int32_t k0, k1, k2;
    fx_acc acc;
    k0 = fx_mul(k, a[0], 30);
    k1 = fx_mul(k, a[1], 30);
    k2 = fx_mul(k, a[2], 30);
    fx_init_u(&acc, FX_DITHER30(t, 1u));
    fx_mac(&acc, k1, b[2]);
    fx_mac(&acc, -k2, b[1]);
    phi[0] = b[0] + (with_a ? a[0] : 0) + fx_floor(&acc, 30);
    fx_init_u(&acc, FX_DITHER30(t, 11u));
    fx_mac(&acc, k2, b[0]);
    fx_mac(&acc, -k0, b[2]);
    phi[1] = b[1] + (with_a ? a[1] : 0) + fx_floor(&acc, 30);
    fx_init_u(&acc, FX_DITHER30(t, 22u));
    fx_mac(&acc, k0, b[1]);
    fx_mac(&acc, -k1, b[0]);
    phi[2] = b[2] + (with_a ? a[2] : 0) + fx_floor(&acc, 30);
}

/* the fixed-point methods: 0..4 and 6 (5 is rk4, not ported) */
static uint8_t fx_method_ok(att_fx_method m)
{
    return (unsigned int)m <= (unsigned int)ATT_FX_RV3_REUSE || m == ATT_FX_RV3_REUSE_POLY;
}

static uint8_t fx_is_reuse(uint8_t m)
{
    return m == (uint8_t)ATT_FX_RV3_REUSE || m == (uint8_t)ATT_FX_RV3_REUSE_POLY;
}

att_status att_fx_phi(att_fx_method method, const att_q30 *d, uint8_t n, att_q30 phi[3])
{
    if (d == 0 || phi == 0) {
        return ATT_E_NULL;
    }
    if (!fx_method_ok(method)) {
        return (att_status)ATT_FX_E_METHOD;
    }
    if (n < 1u || n > 3u || (method == ATT_FX_RV1 && n != 1u) || (method == ATT_FX_RV2 && n != 2u)
        || ((method == ATT_FX_RV3 || method == ATT_FX_RV3_CONING) && n != 3u)) {
        return ATT_E_ARG;
    }
    if (!att__fx_dtheta_ok(d, (uint8_t)(3u * n))) {
        return (att_status)ATT_FX_E_RANGE;
    }
    switch (method) {
    case ATT_FX_RV3:
        att__fx_phi_rv3(d, ATT_FX_K_RV3_13, ATT_FX_K_RV3_23, 0, phi);
        break;
    case ATT_FX_RV3_CONING:
        att__fx_phi_rv3(d, ATT_FX_K_RV3C_13, ATT_FX_K_RV3C_23, 0, phi);
        break;
    case ATT_FX_RV2:
        fx_phi2(d, d + 3, ATT_FX_K_RV2, 1, 0, phi);
        break;
    default: /* rv1, reuse forms */
        if (n == 1u) {
            phi[0] = d[0];
            phi[1] = d[1];
            phi[2] = d[2];
        } else if (n == 2u) {
            fx_phi2(d, d + 3, ATT_FX_K_RV3R_START, 0, 0, phi);
        } else {
            att__fx_phi_reuse(d, d + 3, d + 6, method == ATT_FX_RV3_REUSE_POLY, 0, phi);
        }
        break;
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
    if (!fx_method_ok(method)) {
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
    s->old = 0;
    return ATT_OK;
}

static void fx_copy3(att_q30 *dst, const att_q30 *src)
{
    dst[0] = src[0];
    dst[1] = src[1];
    dst[2] = src[2];
}

/*
 * One increment. The increment is range-checked first; the state changes
 * only when the call succeeds (an update that fails — impossible for a
 * state kept by this module — leaves q, nbuf and the history as they were;
 * buf[2] is scratch).
 */
int att_fx_integ_update(att_fx_integ *s, const att_q30 dtheta[3], att_q30 q_out[4])
{
    att_q30 phi[3];
    att_status st;
    uint8_t m;
    uint32_t t;
    if (s == 0 || dtheta == 0) {
        return ATT_E_NULL;
    }
    if (FX_DBAD(dtheta[0]) || FX_DBAD(dtheta[1]) || FX_DBAD(dtheta[2])) {
        return (att_status)ATT_FX_E_RANGE;
    }
    m = s->method;
    if (m == ATT_FX_RV3 || m == ATT_FX_RV3_CONING) {
        fx_copy3(s->buf + 3u * s->nbuf, dtheta);
        if (s->nbuf < 2u) {
            s->nbuf++;
            return ATT_FX_PENDING;
        }
        t = fx_dither_seed(s->q);
        if (m == ATT_FX_RV3) {
            att__fx_phi_rv3(s->buf, ATT_FX_K_RV3_13, ATT_FX_K_RV3_23, t, phi);
        } else {
            att__fx_phi_rv3(s->buf, ATT_FX_K_RV3C_13, ATT_FX_K_RV3C_23, t, phi);
        }
    } else if (fx_is_reuse(m)) {
        t = fx_dither_seed(s->q);
        if (s->nbuf == 2u) {
            att__fx_phi_reuse(s->buf + 3u * s->old, s->buf + 3u * (s->old ^ 1u), dtheta,
                              m == (uint8_t)ATT_FX_RV3_REUSE_POLY, t, phi);
        } else if (s->nbuf == 1u) {
            fx_phi2(s->buf, dtheta, ATT_FX_K_RV3R_START, 0, t, phi);
        } else {
            fx_copy3(phi, dtheta);
        }
    } else if (m == ATT_FX_RV2) {
        if (s->nbuf == 0u) {
            fx_copy3(s->buf, dtheta);
            s->nbuf = 1;
            return ATT_FX_PENDING;
        }
        t = fx_dither_seed(s->q);
        fx_phi2(s->buf, dtheta, ATT_FX_K_RV2, 1, t, phi);
    } else if (m == ATT_FX_RV1) {
        t = fx_dither_seed(s->q);
        fx_copy3(phi, dtheta);
    } else {
        return (att_status)ATT_FX_E_METHOD;
    }
    st = att__fx_apply(s->q, phi, t);
    if (st != ATT_OK) {
        return st;
    }
    if (fx_is_reuse(m)) {
        if (s->nbuf < 2u) {
            fx_copy3(s->buf + 3u * s->nbuf, dtheta);
            s->nbuf++;
        } else {
            /* overwrite the older one, which becomes the newer */
            fx_copy3(s->buf + 3u * s->old, dtheta);
            s->old ^= 1u;
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

att_status att_fx_integ_batch(att_fx_integ *s, const att_q30 *dtheta, size_t n, att_q30 *q_out, size_t *n_out,
                              size_t *err_index)
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
        const att_q30 *d = dtheta + 3u * i;
        if (FX_DBAD(d[0]) || FX_DBAD(d[1]) || FX_DBAD(d[2])) {
            if (err_index != 0) {
                *err_index = i;
            }
            return (att_status)ATT_FX_E_RANGE;
        }
    }
    for (i = 0; i < n;) {
        /* fast paths (same arithmetic as att_fx_integ_update, no copies):
         * a whole rv3 frame straight from the caller's array, and the reuse forms
         * with its two previous increments also in the array */
        if (s->nbuf == 0u && i + 3u <= n && (s->method == ATT_FX_RV3 || s->method == ATT_FX_RV3_CONING)) {
            att_q30 phi[3];
            uint32_t t = fx_dither_seed(s->q);
            if (s->method == ATT_FX_RV3) {
                att__fx_phi_rv3(dtheta + 3u * i, ATT_FX_K_RV3_13, ATT_FX_K_RV3_23, t, phi);
            } else {
                att__fx_phi_rv3(dtheta + 3u * i, ATT_FX_K_RV3C_13, ATT_FX_K_RV3C_23, t, phi);
            }
            r = att__fx_apply(s->q, phi, t);
            i += 3u;
        } else if (fx_is_reuse(s->method) && i >= 2u) {
            att_q30 phi[3];
            uint32_t t = fx_dither_seed(s->q);
            att__fx_phi_reuse(dtheta + 3u * (i - 2u), dtheta + 3u * (i - 1u), dtheta + 3u * i,
                              s->method == (uint8_t)ATT_FX_RV3_REUSE_POLY, t, phi);
            r = att__fx_apply(s->q, phi, t);
            if (r == ATT_OK && i + 1u == n) { /* leave the history in the state */
                fx_copy3(s->buf, dtheta + 3u * (i - 1u));
                fx_copy3(s->buf + 3, dtheta + 3u * i);
                s->old = 0;
            }
            i += 1u;
        } else {
            r = att_fx_integ_update(s, dtheta + 3u * i, q_out + 4u * m);
            i += 1u;
            if (r == ATT_FX_PENDING) {
                continue;
            }
        }
        if (r < 0) { /* not reachable: inputs checked above, state invariant kept */
            if (err_index != 0) {
                *err_index = i - 1u;
            }
            return (att_status)r;
        }
        q_out[4u * m] = s->q[0];
        q_out[4u * m + 1u] = s->q[1];
        q_out[4u * m + 2u] = s->q[2];
        q_out[4u * m + 3u] = s->q[3];
        ++m;
    }
    if (n_out != 0) {
        *n_out = m;
    }
    return ATT_OK;
}
