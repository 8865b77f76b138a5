/*
 * Test-vector runner: reads vectors written by toolchain/vectors.py (inputs
 * from the NumPy reference's generator), runs the library on them and
 * prints the results for pytest to compare with the reference. Plain C99
 * + stdio, no malloc: it runs on the host, on the bare ARMv4T core under
 * `qemu-arm -cpu ti925t` (newlib semihosting opens the file) and on
 * ARM Linux under qemu-arm.
 *
 * Input (whitespace-separated tokens, '#' starts a comment line):
 *   case ID FUNC N [PARAMS...]   then N records of FUNC's input arity
 * FUNC and PARAMS:
 *   quat_mul (8 -> 4), quat_conj (4 -> 4), quat_normalize (4 -> 4),
 *   rotvec_to_quat (3 -> 4), quat_to_rotvec (4 -> 3), quat_to_dcm (4 -> 9),
 *   dcm_to_quat (9 -> 4), dcm_to_euler (9 -> 3), euler_to_dcm (3 -> 9),
 *   quat_to_euler (4 -> 3), euler_to_quat (3 -> 4), quat_heading (4 -> 1),
 *   dcm_heading (9 -> 1)                 -- the array (_n) forms, PARAMS none;
 *   integ METHOD q0 q1 q2 q3             -- N increments (3) -> a quaternion per update;
 *   rk4 H q0 q1 q2 q3                    -- N rates (3), step H -> a quaternion per update;
 *   link_checksum                        -- N bytes (one record of N values) -> 1;
 *   link_rx BLOCK GAP                    -- N events "byte tick" for receiver B;
 *   link_tx BLOCK SYN_TO ANS_TO ATTEMPTS BYTES... -- N events for sender A;
 *   wden_dwt WAVELET LEVELS, wden_idwt WAVELET LEVELS -- N samples (1) -> N coefficients
 *     (wavedec order) and back;
 *   sensor OVERSAMPLE PERIOD Z0 Z1 Z2 K0 K1 K2 A0 A1 A2 S0 S1 S2 M0..M8 B0 B1 B2 -- N words (3) -> N
 *     increments (3)
 *     (att_sensor_increments; Z zero codes, K scales, A the channel of each body axis, S signs, then
 *     M the 9 correction values row-major and B the 3 biases: att_sensor_set_correction);
 *   wden_stream WAVELET MODE LEVELS BLOCK EDGE_START EDGE_END DETREND -- N samples (1) pushed in one
 *     att_wden_push_n() call, then flushed -> N denoised samples;
 *   align DECL SIX        -- N records f, m (6; SIX = 1: f only, 3) -> N quaternions (att_align_accmag_n);
 *   triad DECL            -- N records f, m (6) -> N quaternions (att_triad_n);
 *   gn DECL METHOD MAXIT  -- N records f, m, q0 (10) -> N quaternions (att_gn_solve_n, defaults but max_iter);
 *   align_window DECL     -- N samples gyr, acc, mag (9) -> 1 quaternion (att_align_window_*, defaults);
 *   magcal MODEL          -- N raw field samples (3) -> 1 record h, S, field (13) (att_magcal_*);
 *   magcal2d              -- N samples (3) -> 1 record h, S, field (13) (att_magcal2d_*);
 *   magcal_apply H0..2 S0..8 -- N samples (3) -> N corrected samples (3) (att_magcal_apply_n);
 *     WAVELET = haar|db2|db4, MODE = soft|hard;
 *     event byte: 0..255 = sink it, -1 = poll only, -2 = (sender) start the block.
 *     After each event the machine is polled until NONE or IDLE; output rows
 *     "event kind value": kind 0 = sink/start result, 1 = poll result,
 *     2 = byte handed out; then one row per statistics counter (kind 3).
 * Output per case:
 *   = ID STATUS ERR_INDEX NOUT           (ERR_INDEX -1 when none)
 *   NOUT lines of output values
 * and a last line "vectors: C cases, S bytes of att_real".
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "attitude/attitude.h"

enum {
    WDEN_BLOCK_MAX = 256, /* largest denoiser block of the vectors */
    MAX_REC = 2048,
    MAX_VALS = MAX_REC * 9,
    MAX_OUT = MAX_REC * 9
};

static att_real in_buf[MAX_VALS];
static att_real in_buf2[MAX_VALS];
static att_real out_buf[MAX_OUT];
static FILE *in;

#if defined(ATT_REAL_F32)
#define DIGITS 9
#else
#define DIGITS 17
#endif

static int token(char *tok, size_t n)
{
    int c;
    size_t k = 0;
    for (;;) { /* skip blanks and comment lines */
        c = fgetc(in);
        if (c == EOF)
            return -1;
        if (c == '#') {
            while (c != '\n' && c != EOF)
                c = fgetc(in);
            continue;
        }
        if (c != ' ' && c != '\t' && c != '\n' && c != '\r')
            break;
    }
    while (c != EOF && c != ' ' && c != '\t' && c != '\n' && c != '\r') {
        if (k + 1 < n)
            tok[k++] = (char)c;
        c = fgetc(in);
    }
    tok[k] = '\0';
    return 0;
}

static int number(double *v)
{
    char tok[64], *end;
    if (token(tok, sizeof tok) != 0)
        return -1;
    *v = strtod(tok, &end);
    return *end == '\0' ? 0 : -1;
}

static int read_values(att_real *dst, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) {
        double v;
        if (number(&v) != 0)
            return -1;
        dst[i] = (att_real)v;
    }
    return 0;
}

static void print_records(const att_real *v, size_t nrec, size_t arity)
{
    size_t r, j;
    for (r = 0; r < nrec; r++) {
        for (j = 0; j < arity; j++)
            printf(j ? " %.*g" : "%.*g", DIGITS, (double)v[r * arity + j]);
        putchar('\n');
    }
}

typedef att_status (*map_fn)(const att_real *, att_real *, size_t, size_t *);

static const struct {
    const char *name;
    size_t in, out;
    map_fn fn;
} maps[] = {
    { "quat_normalize", 4, 4, att_quat_normalize_n }, { "rotvec_to_quat", 3, 4, att_rotvec_to_quat_n },
    { "quat_to_rotvec", 4, 3, att_quat_to_rotvec_n }, { "quat_to_dcm", 4, 9, att_quat_to_dcm_n },
    { "dcm_to_quat", 9, 4, att_dcm_to_quat_n },       { "dcm_to_euler", 9, 3, att_dcm_to_euler_n },
    { "euler_to_dcm", 3, 9, att_euler_to_dcm_n },     { "quat_to_euler", 4, 3, att_quat_to_euler_n },
    { "euler_to_quat", 3, 4, att_euler_to_quat_n },   { "quat_heading", 4, 1, att_quat_heading_n },
    { "dcm_heading", 9, 1, att_dcm_heading_n },
};

static int wavelet_code(const char *name)
{
    static const char *names[] = { "haar", "db2", "db4" };
    int w;
    for (w = 0; w < 3; w++)
        if (strcmp(name, names[w]) == 0)
            return w;
    return -1;
}

static void result(const char *id, int status, long err, size_t nout)
{
    printf("= %s %d %ld %lu\n", id, status, err, (unsigned long)nout);
}

static size_t nrows;

static void row(size_t ev, int kind, long value)
{
    out_buf[3 * nrows] = (att_real)ev;
    out_buf[3 * nrows + 1] = (att_real)kind;
    out_buf[3 * nrows + 2] = (att_real)value;
    nrows++;
}

/* Transcript of one link state machine (records: byte tick). */
static int run_link(const char *id, int tx, size_t n)
{
    att_link_receiver r;
    att_link_receiver_config rc;
    att_link_sender s;
    att_link_sender_config sc;
    static uint8_t block[ATT_LINK_BLOCK_MAX], rxbuf[ATT_LINK_BLOCK_MAX];
    double v[4];
    size_t i, k;
    int st;
    if (number(&v[0]) != 0 || number(&v[1]) != 0 || v[0] < 1 || v[0] > ATT_LINK_BLOCK_MAX)
        return -1;
    if (tx) {
        if (number(&v[2]) != 0 || number(&v[3]) != 0)
            return -1;
        att_link_sender_config_init(&sc, (uint8_t)v[0]);
        sc.syn_timeout = (uint16_t)v[1];
        sc.answer_timeout = (uint16_t)v[2];
        sc.max_attempts = (uint8_t)v[3];
        for (k = 0; k < (size_t)v[0]; k++) {
            double b;
            if (number(&b) != 0)
                return -1;
            block[k] = (uint8_t)b;
        }
        st = att_link_sender_init(&s, &sc);
    } else {
        att_link_receiver_config_init(&rc, (uint8_t)v[0]);
        rc.gap_timeout = (uint16_t)v[1];
        st = att_link_receiver_init(&r, &rc, rxbuf);
    }
    if (st != ATT_OK || read_values(in_buf, 2 * n) != 0)
        return -1;
    nrows = 0;
    for (i = 0; i < n; i++) {
        long byte = (long)in_buf[2 * i];
        uint16_t tick = (uint16_t)(long)in_buf[2 * i + 1];
        int guard;
        if (3 * (nrows + 2 * ATT_LINK_BLOCK_MAX + 16) > MAX_OUT)
            return -1; /* transcript too long for the output buffer */
        if (byte == -2 && tx)
            row(i, 0, att_link_sender_start(&s, block, tick));
        else if (byte >= 0)
            row(i, 0,
                tx ? att_link_sender_sink(&s, (uint8_t)byte, tick)
                   : att_link_receiver_sink(&r, (uint8_t)byte, tick));
        for (guard = 0; guard < 2 * ATT_LINK_BLOCK_MAX + 8; guard++) {
            uint8_t out = 0;
            att_link_result res =
                tx ? att_link_sender_poll(&s, tick, &out) : att_link_receiver_poll(&r, tick, &out);
            row(i, 1, res);
            if (res == ATT_LINK_SEND)
                row(i, 2, out);
            if (res == ATT_LINK_NONE || res == ATT_LINK_IDLE || res < 0)
                break;
        }
    }
    if (tx) {
        const att_link_sender_stats *t = &s.stats;
        long sv[6];
        sv[0] = t->blocks_sent;
        sv[1] = t->blocks_accepted;
        sv[2] = t->naks;
        sv[3] = t->timeouts;
        sv[4] = t->gave_up;
        sv[5] = t->bytes_discarded;
        for (k = 0; k < 6; k++)
            row(n, 3, sv[k]);
    } else {
        const att_link_receiver_stats *t = &r.stats;
        long sv[6];
        sv[0] = (long)t->syns;
        sv[1] = (long)t->blocks_accepted;
        sv[2] = (long)t->naks;
        sv[3] = (long)t->timeouts;
        sv[4] = (long)t->resyncs;
        sv[5] = (long)t->bytes_discarded;
        for (k = 0; k < 6; k++)
            row(n, 3, sv[k]);
    }
    result(id, ATT_OK, -1L, nrows);
    print_records(out_buf, nrows, 3);
    return 0;
}

/* The wavelet denoiser: the block transform both ways, and a whole stream. */
static int run_wden(const char *id, const char *fn, size_t n)
{
    static att_real ring[WDEN_BLOCK_MAX], scratch[2 * WDEN_BLOCK_MAX];
    char wname[16], mname[16];
    double v[5];
    int st;
    size_t nout = 0, err = 0, got = 0;
    if (token(wname, sizeof wname) != 0 || wavelet_code(wname) < 0)
        return -1;
    if (strcmp(fn, "wden_dwt") == 0 || strcmp(fn, "wden_idwt") == 0) {
        if (number(&v[0]) != 0 || read_values(in_buf, n) != 0)
            return -1;
        st = strcmp(fn, "wden_dwt") == 0
                 ? att_wden_dwt(wavelet_code(wname), (unsigned int)v[0], in_buf, n, out_buf, in_buf2)
                 : att_wden_idwt(wavelet_code(wname), (unsigned int)v[0], in_buf, n, out_buf, in_buf2);
        result(id, st, st == ATT_OK ? -1L : 0L, st == ATT_OK ? n : 0);
        print_records(out_buf, st == ATT_OK ? n : 0, 1);
        return 0;
    }
    if (strcmp(fn, "wden_stream") == 0) {
        att_wden_config cfg;
        att_wden s;
        if (token(mname, sizeof mname) != 0 || number(&v[0]) != 0 || number(&v[1]) != 0 || number(&v[2]) != 0
            || number(&v[3]) != 0 || number(&v[4]) != 0 || read_values(in_buf, n) != 0)
            return -1;
        cfg.wavelet = wavelet_code(wname);
        cfg.mode = strcmp(mname, "hard") == 0 ? ATT_WDEN_HARD : ATT_WDEN_SOFT;
        cfg.levels = (unsigned int)v[0];
        cfg.block = (size_t)v[1];
        cfg.edge_start = (size_t)v[2];
        cfg.edge_end = (size_t)v[3];
        cfg.detrend = (int)v[4];
        st = att_wden_init(&s, &cfg, ring, WDEN_BLOCK_MAX, scratch, 2 * WDEN_BLOCK_MAX);
        if (st == ATT_OK)
            st = att_wden_push_n(&s, in_buf, n, out_buf, MAX_OUT, &nout, &err);
        if (st == ATT_OK)
            st = att_wden_flush(&s, out_buf + nout, MAX_OUT - nout, &got);
        result(id, st, st == ATT_OK ? -1L : (long)err, st == ATT_OK ? nout + got : 0);
        print_records(out_buf, st == ATT_OK ? nout + got : 0, 1);
        return 0;
    }
    return -1;
}

/* Sensor words to increments (attitude/sensor.h). */
static int run_sensor(const char *id, size_t n)
{
    static uint16_t words[3 * MAX_REC];
    double p[26];
    att_real zero[3], scale[3], mat[9], bias[3];
    uint8_t axis[3];
    int8_t sign[3];
    att_sensor s;
    size_t i, err = 0;
    att_status st;
    for (i = 0; i < 26; i++)
        if (number(&p[i]) != 0)
            return -1;
    for (i = 0; i < 3; i++) {
        zero[i] = (att_real)p[2 + i];
        scale[i] = (att_real)p[5 + i];
        axis[i] = (uint8_t)p[8 + i];
        sign[i] = (int8_t)p[11 + i];
        bias[i] = (att_real)p[23 + i];
    }
    for (i = 0; i < 9; i++)
        mat[i] = (att_real)p[14 + i];
    if (read_values(in_buf, 3 * n) != 0)
        return -1;
    for (i = 0; i < 3 * n; i++)
        words[i] = (uint16_t)in_buf[i];
    st = att_sensor_init(&s, zero, scale, axis, sign);
    if (st == ATT_OK)
        st = att_sensor_set_correction(&s, mat, bias);
    if (st == ATT_OK)
        st = att_sensor_increments(&s, words, n, (uint8_t)p[0], (att_real)p[1], out_buf, &err);
    result(id, st, st == ATT_OK ? -1L : (long)err, st == ATT_OK ? n : 0);
    print_records(out_buf, st == ATT_OK ? n : 0, 3);
    return 0;
}

/* Aiding solvers (attitude/aiding.h); the batch forms report the first
 * failed record as ERR_INDEX. */
static int first_bad(const int *status, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (status[i] != ATT_OK)
            return (int)i;
    return -1;
}

static void magcal_record(const att_magcal_result *r, att_real *o)
{
    int i;
    for (i = 0; i < 3; i++)
        o[i] = r->h[i];
    for (i = 0; i < 9; i++)
        o[3 + i] = r->S[i];
    o[12] = r->field;
}

static int run_aiding(const char *id, const char *fn, size_t n)
{
    static int status[MAX_REC];
    static att_real f[3 * MAX_REC], m[3 * MAX_REC], q0[4 * MAX_REC];
    double p[12];
    size_t i;
    int bad;
    att_status st;
    if (strcmp(fn, "align") == 0 || strcmp(fn, "triad") == 0 || strcmp(fn, "gn") == 0) {
        int six = 0, gn = strcmp(fn, "gn") == 0, method = 0;
        if (number(&p[0]) != 0)
            return -1;
        if (strcmp(fn, "align") == 0 || gn) {
            if (number(&p[1]) != 0)
                return -1;
            six = !gn && p[1] != 0.0;
            method = gn ? (int)p[1] : 0;
        }
        if (gn && number(&p[2]) != 0)
            return -1;
        for (i = 0; i < n; i++)
            if (read_values(f + 3 * i, 3) != 0 || (!six && read_values(m + 3 * i, 3) != 0)
                || (gn && read_values(q0 + 4 * i, 4) != 0))
                return -1;
        if (gn) {
            att_gn_settings s;
            att_gn_defaults(&s);
            s.method = method;
            s.max_iter = (unsigned int)p[2];
            st = att_gn_solve_n(f, m, (att_real)p[0], q0, &s, out_buf, n, status, NULL, NULL);
        } else if (strcmp(fn, "triad") == 0) {
            st = att_triad_n(f, m, (att_real)p[0], out_buf, n, status);
        } else {
            st = att_align_accmag_n(f, six ? NULL : m, (att_real)p[0], out_buf, n, status);
        }
        bad = st == ATT_OK ? -1 : first_bad(status, n);
        result(id, st, (long)bad, st == ATT_OK ? n : 0);
        print_records(out_buf, st == ATT_OK ? n : 0, 4);
        return 0;
    }
    if (strcmp(fn, "align_window") == 0) {
        att_align_window w;
        att_align_window_settings s;
        att_real g[3], a[3], mm[3];
        if (number(&p[0]) != 0)
            return -1;
        att_align_window_defaults(&s);
        s.declination_rad = (att_real)p[0];
        st = att_align_window_init(&w, &s);
        for (i = 0; i < n; i++) {
            if (read_values(g, 3) != 0 || read_values(a, 3) != 0 || read_values(mm, 3) != 0)
                return -1;
            if (st == ATT_OK)
                st = att_align_window_add(&w, g, a, mm);
        }
        if (st == ATT_OK)
            st = att_align_window_solve(&w, out_buf);
        result(id, st, st == ATT_OK ? -1L : 0L, st == ATT_OK ? 1 : 0);
        print_records(out_buf, st == ATT_OK ? 1 : 0, 4);
        return 0;
    }
    if (strcmp(fn, "magcal") == 0 || strcmp(fn, "magcal2d") == 0) {
        att_magcal c;
        att_magcal2d c2;
        att_magcal_result r;
        int two = strcmp(fn, "magcal2d") == 0;
        size_t err = 0;
        if (!two && number(&p[0]) != 0)
            return -1;
        if (read_values(in_buf, 3 * n) != 0)
            return -1;
        if (two) {
            st = att_magcal2d_init(&c2);
            for (i = 0; i < n && st == ATT_OK; i++)
                st = att_magcal2d_add(&c2, in_buf + 3 * i);
            err = i - 1;
            if (st == ATT_OK)
                st = att_magcal2d_solve(&c2, &r);
        } else {
            st = att_magcal_init(&c, NULL);
            if (st == ATT_OK)
                st = att_magcal_add_n(&c, in_buf, n, &err);
            if (st == ATT_OK)
                st = att_magcal_solve(&c, (int)p[0], &r);
        }
        if (st == ATT_OK)
            magcal_record(&r, out_buf);
        result(id, st, st == ATT_OK ? -1L : (long)err, st == ATT_OK ? 1 : 0);
        print_records(out_buf, st == ATT_OK ? 1 : 0, 13);
        return 0;
    }
    if (strcmp(fn, "magcal_apply") == 0) {
        att_magcal_result r;
        size_t err = 0;
        for (i = 0; i < 12; i++)
            if (number(&p[i]) != 0)
                return -1;
        for (i = 0; i < 3; i++)
            r.h[i] = (att_real)p[i];
        for (i = 0; i < 9; i++)
            r.S[i] = (att_real)p[3 + i];
        r.field = 1;
        if (read_values(in_buf, 3 * n) != 0)
            return -1;
        st = att_magcal_apply_n(&r, in_buf, out_buf, n, &err);
        result(id, st, st == ATT_OK ? -1L : (long)err, st == ATT_OK ? n : 0);
        print_records(out_buf, st == ATT_OK ? n : 0, 3);
        return 0;
    }
    return -1;
}

static int run_case(const char *id, const char *fn, size_t n)
{
    size_t i, err = 0;
    att_status st;
    if (n > MAX_REC)
        return -1;
    for (i = 0; i < sizeof maps / sizeof maps[0]; i++) {
        if (strcmp(fn, maps[i].name) != 0)
            continue;
        if (read_values(in_buf, n * maps[i].in) != 0)
            return -1;
        st = maps[i].fn(in_buf, out_buf, n, &err);
        if (st == ATT_OK)
            err = n;
        result(id, st, st == ATT_OK ? -1L : (long)err, err);
        print_records(out_buf, err, maps[i].out);
        return 0;
    }
    if (strcmp(fn, "quat_mul") == 0) {
        for (i = 0; i < n; i++)
            if (read_values(in_buf + 4 * i, 4) != 0 || read_values(in_buf2 + 4 * i, 4) != 0)
                return -1;
        st = att_quat_mul_n(in_buf, in_buf2, out_buf, n, &err);
        if (st == ATT_OK)
            err = n;
        result(id, st, st == ATT_OK ? -1L : (long)err, err);
        print_records(out_buf, err, 4);
        return 0;
    }
    if (strcmp(fn, "quat_conj") == 0) {
        if (read_values(in_buf, 4 * n) != 0)
            return -1;
        for (i = 0; i < n; i++)
            att_quat_conj(in_buf + 4 * i, out_buf + 4 * i);
        result(id, ATT_OK, -1L, n);
        print_records(out_buf, n, 4);
        return 0;
    }
    if (strcmp(fn, "link_checksum") == 0) {
        uint8_t bytes[256];
        if (n > sizeof bytes || read_values(in_buf, n) != 0)
            return -1;
        for (i = 0; i < n; i++)
            bytes[i] = (uint8_t)in_buf[i];
        out_buf[0] = (att_real)att_link_checksum(bytes, (uint8_t)n);
        result(id, ATT_OK, -1L, 1);
        print_records(out_buf, 1, 1);
        return 0;
    }
    if (strcmp(fn, "link_rx") == 0 || strcmp(fn, "link_tx") == 0)
        return run_link(id, strcmp(fn, "link_tx") == 0, n);
    if (strncmp(fn, "wden_", 5) == 0)
        return run_wden(id, fn, n);
    if (strcmp(fn, "sensor") == 0)
        return run_sensor(id, n);
    if (strcmp(fn, "align") == 0 || strcmp(fn, "triad") == 0 || strcmp(fn, "gn") == 0
        || strncmp(fn, "align_", 6) == 0 || strncmp(fn, "magcal", 6) == 0)
        return run_aiding(id, fn, n);
    if (strcmp(fn, "integ") == 0 || strcmp(fn, "rk4") == 0) {
        char mname[32];
        att_real q0[4], h = 0;
        att_integ s;
        size_t nout = 0;
        int rk4 = strcmp(fn, "rk4") == 0;
        att_method m = ATT_METHOD_RK4;
        if (rk4) {
            if (read_values(&h, 1) != 0)
                return -1;
        } else {
            if (token(mname, sizeof mname) != 0 || att_integ_method_from_name(mname, &m) != ATT_OK)
                return -1;
        }
        if (read_values(q0, 4) != 0 || read_values(in_buf, 3 * n) != 0)
            return -1;
        st = att_integ_init(&s, m, q0);
        if (st == ATT_OK) {
            if (att_integ_outputs(&s, n) > MAX_OUT / 4)
                return -1;
            st = rk4 ? att_integ_rk4_batch(&s, in_buf, n, &h, 1, out_buf, &nout, &err)
                     : att_integ_batch(&s, in_buf, n, out_buf, &nout, &err);
        }
        result(id, st, st == ATT_OK ? -1L : (long)err, nout);
        print_records(out_buf, nout, 4);
        return 0;
    }
    return -1;
}

int main(int argc, char **argv)
{
    char tok[64], id[64], fn[64];
    unsigned long cases = 0;
    in = argc > 1 ? fopen(argv[1], "r") : stdin;
    if (in == NULL) {
        printf("vectors: cannot open %s\n", argv[1]);
        return 2;
    }
    while (token(tok, sizeof tok) == 0) {
        double n;
        if (strcmp(tok, "case") != 0 || token(id, sizeof id) != 0 || token(fn, sizeof fn) != 0
            || number(&n) != 0 || n < 0) {
            printf("vectors: malformed input near '%s' after %lu cases\n", tok, cases);
            return 2;
        }
        if (run_case(id, fn, (size_t)n) != 0) {
            printf("vectors: bad case %s (%s, %lu records)\n", id, fn, (unsigned long)n);
            return 2;
        }
        cases++;
    }
    printf("vectors: %lu cases, %d bytes of att_real\n", cases, att_real_size());
    return 0;
}
