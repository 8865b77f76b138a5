/* libattitude — wavelet threshold denoiser: the stream of overlapping
 * windows (see denoise.h, docs/denoise.md). */
#include "attitude/denoise.h"

#include "att_math.h"
#include "denoise_internal.h"

int att_wden_init(att_wden *s, const att_wden_config *cfg, att_real *state, size_t state_len,
                  att_real *scratch, size_t scratch_len)
{
    int st;
    if (s == NULL || cfg == NULL || state == NULL || scratch == NULL)
        return ATT_E_NULL;
    st = att_wden_config_check(cfg);
    if (st != ATT_OK)
        return st;
    if (state_len < att_wden_state_len(cfg) || scratch_len < att_wden_scratch_len(cfg))
        return ATT_E_BUFFER;
    s->cfg = *cfg;
    s->ring = state;
    s->scratch = scratch;
    return att_wden_reset(s);
}

int att_wden_reset(att_wden *s)
{
    if (s == NULL)
        return ATT_E_NULL;
    s->head = 0;
    s->fill = 0;
    s->since = 0;
    s->pending = 0;
    s->started = 0;
    s->windows = 0;
    s->sigma = ATT_R(0.0);
    return ATT_OK;
}

size_t att_wden_outputs(const att_wden *s, size_t n)
{
    const size_t nb = s->cfg.block, ee = s->cfg.edge_end, hop = nb - s->cfg.edge_start - ee;
    if (!s->started) {
        if (n < nb - s->fill)
            return 0;
        n -= nb - s->fill; /* samples after the one that completes the first window */
        return (nb - ee) + (n / hop) * hop;
    }
    return ((s->since + n) / hop) * hop;
}

size_t att_wden_pending(const att_wden *s)
{
    return s->pending;
}

/* Denoise the window of the last N samples (the ring is full) and write its
 * positions [a, b), corrected to the input's sum over them, to out. Only
 * sigma and the window count change in the state, and only on success. */
static int run_window(att_wden *s, size_t a, size_t b, att_real *out)
{
    const size_t n = s->cfg.block;
    att_real *c = s->scratch;
    att_real sum_in = ATT_R(0.0), sum_out = ATT_R(0.0), corr, sigma = ATT_R(0.0);
    size_t i, j = s->head; /* the oldest sample */
    int st;
    for (i = 0; i < n; i++) {
        c[i] = s->ring[j];
        if (++j == n)
            j = 0;
    }
    for (i = a; i < b; i++)
        sum_in += c[i];
    st = att__wden_block_core(&s->cfg, c, c + n, &sigma);
    if (st != ATT_OK)
        return st;
    for (i = a; i < b; i++)
        sum_out += c[i];
    corr = (sum_in - sum_out) / (att_real)(b - a);
    for (i = a; i < b; i++) {
        out[i - a] = c[i] + corr;
        if (!isfinite(out[i - a]))
            return ATT_E_WDEN_OVERFLOW;
    }
    s->sigma = sigma;
    s->windows++;
    return ATT_OK;
}

int att_wden_push(att_wden *s, att_real x, att_real *out)
{
    size_t nb, es, ee, hop, head;
    att_real overwritten;
    int st, produced;
    if (s == NULL || out == NULL)
        return ATT_E_NULL;
    if (!isfinite(x))
        return ATT_E_NONFINITE;
    nb = s->cfg.block;
    es = s->cfg.edge_start;
    ee = s->cfg.edge_end;
    hop = nb - es - ee;
    head = s->head;
    overwritten = s->ring[head]; /* kept for the roll-back on overflow */
    s->ring[head] = x;
    s->head = head + 1 == nb ? 0 : head + 1;
    if (!s->started) {
        if (++s->fill < nb) {
            s->pending++;
            return 0;
        }
        st = run_window(s, 0, nb - ee, out); /* the first window outputs from the stream's start */
        produced = (int)(nb - ee);
    } else {
        if (s->since + 1 < hop) {
            s->since++;
            s->pending++;
            return 0;
        }
        st = run_window(s, es, nb - ee, out);
        produced = (int)hop;
    }
    if (st != ATT_OK) { /* state as before the call */
        s->ring[head] = overwritten;
        s->head = head;
        if (!s->started)
            s->fill--;
        return st;
    }
    s->started = 1;
    s->since = 0;
    s->pending = s->pending + 1 - (size_t)produced;
    return produced;
}

int att_wden_push_n(att_wden *s, const att_real *x, size_t n, att_real *out, size_t out_cap, size_t *n_out,
                    size_t *err_index)
{
    size_t i, k = 0;
    if (n_out != NULL)
        *n_out = 0;
    if (s == NULL || (n > 0 && x == NULL))
        return ATT_E_NULL;
    for (i = 0; i < n; i++) {
        if (!isfinite(x[i])) {
            if (err_index != NULL)
                *err_index = i;
            return ATT_E_NONFINITE;
        }
    }
    if (att_wden_outputs(s, n) > out_cap)
        return ATT_E_BUFFER;
    if (out == NULL && out_cap > 0)
        return ATT_E_NULL;
    for (i = 0; i < n; i++) {
        int r = att_wden_push(s, x[i], out != NULL ? out + k : s->scratch);
        if (r < 0) {
            if (err_index != NULL)
                *err_index = i;
            if (n_out != NULL)
                *n_out = k;
            return r;
        }
        k += (size_t)r;
    }
    if (n_out != NULL)
        *n_out = k;
    return ATT_OK;
}

int att_wden_flush(att_wden *s, att_real *out, size_t out_cap, size_t *n_out)
{
    const size_t nb = s != NULL ? s->cfg.block : 0;
    int st;
    if (n_out != NULL)
        *n_out = 0;
    if (s == NULL)
        return ATT_E_NULL;
    if (s->pending == 0)
        return att_wden_reset(s);
    if (!s->started)
        return ATT_E_WDEN_SHORT;
    if (out == NULL)
        return ATT_E_NULL;
    if (out_cap < s->pending)
        return ATT_E_BUFFER;
    st = run_window(s, nb - s->pending, nb, out); /* the last N samples; no edge dropped at the end */
    if (st != ATT_OK)
        return st;
    if (n_out != NULL)
        *n_out = s->pending;
    return att_wden_reset(s);
}
