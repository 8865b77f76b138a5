/*
 * libattitude — sensor words to body-frame values (see attitude/sensor.h).
 */
#include "attitude/sensor.h"

#include "att_math.h"

att_status att_sensor_init(att_sensor *s, const att_real zero[3], const att_real scale[3],
                           const uint8_t axis[3], const int8_t sign[3])
{
    uint8_t seen = 0;
    int i;
    if (s == NULL || zero == NULL || scale == NULL) {
        return ATT_E_NULL;
    }
    for (i = 0; i < 3; i++) {
        if (!isfinite(zero[i]) || !isfinite(scale[i])) {
            return ATT_E_NONFINITE;
        }
        if (zero[i] < (att_real)0 || zero[i] > (att_real)ATT_SENSOR_ZERO_MAX || scale[i] == (att_real)0) {
            return ATT_E_ARG;
        }
        if (axis != NULL) {
            if (axis[i] > 2u || (seen & (1u << axis[i])) != 0u) {
                return ATT_E_ARG;
            }
            seen = (uint8_t)(seen | (1u << axis[i]));
        }
        if (sign != NULL && sign[i] != 1 && sign[i] != -1) {
            return ATT_E_ARG;
        }
    }
    for (i = 0; i < 3; i++) {
        s->zero[i] = zero[i];
        s->scale[i] = scale[i];
        s->axis[i] = axis != NULL ? axis[i] : (uint8_t)i;
        s->sign[i] = sign != NULL ? sign[i] : (int8_t)1;
        s->bias[i] = 0;
    }
    for (i = 0; i < 9; i++) {
        s->mat[i] = i % 4 == 0 ? ATT_R(1.0) : ATT_R(0.0);
    }
    s->plain = 1u;
    return ATT_OK;
}

static att_real det3(const att_real m[9])
{
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6])
           + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

att_status att_sensor_set_correction(att_sensor *s, const att_real mat[9], const att_real bias[3])
{
    att_real det;
    uint8_t plain = 1u;
    int i;
    if (s == NULL || mat == NULL || bias == NULL) {
        return ATT_E_NULL;
    }
    for (i = 0; i < 9; i++) {
        if (!isfinite(mat[i])) {
            return ATT_E_NONFINITE;
        }
        if (mat[i] != (i % 4 == 0 ? ATT_R(1.0) : ATT_R(0.0))) {
            plain = 0u;
        }
    }
    if (!att__finite3(bias)) {
        return ATT_E_NONFINITE;
    }
    det = det3(mat);
    if (!isfinite(det)) {
        return ATT_E_ARG; /* entries so large that the determinant overflows: no correction */
    }
    if (att_fabs(det) * (att_real)ATT_SENSOR_DET_RECIP < ATT_R(1.0)) {
        return ATT_E_ARG;
    }
    for (i = 0; i < 9; i++) {
        s->mat[i] = mat[i];
    }
    for (i = 0; i < 3; i++) {
        s->bias[i] = bias[i];
        if (bias[i] != (att_real)0) {
            plain = 0u;
        }
    }
    s->plain = plain;
    return ATT_OK;
}

/* out = M (v - b), in att_magcal_apply's order (attitude/sensor.h). */
static void correct(const att_sensor *s, att_real v[3])
{
    att_real d[3];
    const att_real *m = s->mat;
    int i;
    for (i = 0; i < 3; i++) {
        d[i] = v[i] - s->bias[i];
    }
    for (i = 0; i < 3; i++) {
        v[i] = m[3 * i] * d[0] + m[3 * i + 1] * d[1] + m[3 * i + 2] * d[2];
    }
}

/* The three corrected values of one sample into v (unchecked output). */
static att_status values(const att_sensor *s, const uint16_t w[3], uint8_t n, att_real v[3])
{
    int i;
    uint8_t c;
    uint32_t max = (uint32_t)n * (uint32_t)ATT_BLOCK_CODE_MAX;
    for (i = 0; i < 3; i++) {
        if ((uint32_t)w[i] > max) {
            return ATT_E_RANGE;
        }
    }
    for (i = 0; i < 3; i++) {
        c = s->axis[i];
        v[i] = (att_real)s->sign[i] * ((att_real)w[c] / (att_real)n - s->zero[c]) * s->scale[c];
    }
    if (!s->plain) {
        correct(s, v);
    }
    return ATT_OK;
}

att_status att_sensor_convert(const att_sensor *s, const uint16_t words[3], uint8_t n, att_real out[3])
{
    att_real v[3];
    att_status st;
    if (s == NULL || words == NULL || out == NULL) {
        return ATT_E_NULL;
    }
    if (n < 1u || n > (uint8_t)ATT_BLOCK_OVERSAMPLE_MAX) {
        return ATT_E_ARG;
    }
    st = values(s, words, n, v);
    if (st != ATT_OK) {
        return st;
    }
    if (!att__finite3(v)) {
        return ATT_E_RANGE; /* a huge scale: no finite value */
    }
    out[0] = v[0];
    out[1] = v[1];
    out[2] = v[2];
    return ATT_OK;
}

att_status att_sensor_increments(const att_sensor *s, const uint16_t *words, size_t m, uint8_t n,
                                 att_real period, att_real *dtheta, size_t *err_index)
{
    att_real v[3];
    att_status st;
    size_t k;
    int i;
    if (s == NULL || (m > 0u && (words == NULL || dtheta == NULL))) {
        return ATT_E_NULL;
    }
    if (!isfinite(period)) {
        return ATT_E_NONFINITE;
    }
    if (n < 1u || n > (uint8_t)ATT_BLOCK_OVERSAMPLE_MAX || !(period > (att_real)0)) {
        return ATT_E_ARG;
    }
    /* check every sample before writing any increment */
    for (k = 0; k < m; k++) {
        st = values(s, words + 3u * k, n, v);
        for (i = 0; st == ATT_OK && i < 3; i++) {
            if (!isfinite(v[i] * period)) {
                st = ATT_E_RANGE;
            }
        }
        if (st != ATT_OK) {
            if (err_index != NULL) {
                *err_index = k;
            }
            return st;
        }
    }
    for (k = 0; k < m; k++) {
        (void)values(s, words + 3u * k, n, v);
        for (i = 0; i < 3; i++) {
            dtheta[3u * k + (size_t)i] = v[i] * period;
        }
    }
    return ATT_OK;
}
