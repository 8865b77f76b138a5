/* attitude-rx: command line (getopt_long) and config file. */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rx.h"

static const struct {
    const char *name;
    att_method method;
} methods[] = {
    { "rv1", ATT_METHOD_RV1 },
    { "rv2", ATT_METHOD_RV2 },
    { "rv3", ATT_METHOD_RV3 },
    { "rv3-coning", ATT_METHOD_RV3_CONING },
    { "rv3-reuse", ATT_METHOD_RV3_REUSE },
    { "rv3-reuse-poly", ATT_METHOD_RV3_REUSE_POLY },
    { "rk4", ATT_METHOD_RK4 },
};

int rx_sensor_init(const rx_sensor_cfg *c, att_sensor *s)
{
    att_real zero[3], scale[3], mat[9], bias[3];
    uint8_t axis[3];
    int8_t sign[3];
    att_sensor t;
    int i, rc;
    for (i = 0; i < 3; i++) {
        zero[i] = (att_real)c->zero[i];
        scale[i] = (att_real)c->scale[i];
        axis[i] = (uint8_t)c->axis_src[i];
        sign[i] = (int8_t)c->axis_sign[i];
        bias[i] = (att_real)c->bias[i];
    }
    for (i = 0; i < 9; i++)
        mat[i] = (att_real)c->mat[i];
    if ((rc = att_sensor_init(&t, zero, scale, axis, sign)) != ATT_OK
        || (rc = att_sensor_set_correction(&t, mat, bias)) != ATT_OK)
        return rc;
    *s = t;
    return ATT_OK;
}

/* The filter's settings by field name (attitude/ahrs.h): every att_real field of
 * att_ahrs_settings, from the library's own table (att_ahrs_setting_field: a field added
 * to the header is read here with no change); method is the shared "method" key. */
/* The i-th real field of *set (the library's table: att_ahrs_setting_field). */
static att_real *ahrs_field(att_ahrs_settings *set, size_t i)
{
    size_t offset = 0;
    (void)att_ahrs_setting_field(i, &offset);
    return (att_real *)(void *)((char *)set + offset);
}

const char *rx_ahrs_setting(size_t i, const att_ahrs_settings *set, double *value)
{
    if (i >= ATT_AHRS_REAL_SETTINGS)
        return NULL;
    *value = (double)*ahrs_field((att_ahrs_settings *)(uintptr_t)set, i);
    return att_ahrs_setting_field(i, NULL);
}

static const char *const estimator_names[] = { "auto", "ahrs", "integrator" };

const char *rx_estimator_name(rx_estimator e)
{
    return (unsigned)e < 3u ? estimator_names[e] : "?";
}

rx_estimator rx_estimator_for(rx_estimator chosen, unsigned channels)
{
    const unsigned aided = ATT_BLOCK_CH_ACC | ATT_BLOCK_CH_MAG;
    if (chosen == RX_EST_AUTO)
        return (channels & aided) == aided ? RX_EST_AHRS : RX_EST_INTEGRATOR;
    if (chosen == RX_EST_AHRS && !(channels & ATT_BLOCK_CH_ACC))
        return RX_EST_INTEGRATOR; /* no accelerometer: nothing to align or aid with (a warning) */
    return chosen;
}

const char *rx_method_name(att_method m)
{
    size_t i;
    for (i = 0; i < sizeof methods / sizeof methods[0]; i++)
        if (methods[i].method == m)
            return methods[i].name;
    return "?";
}

static void sensor_defaults(rx_sensor_cfg *s, double zero, double scale)
{
    int i;
    for (i = 0; i < 3; i++) {
        s->zero[i] = zero;
        s->scale[i] = scale;
        s->axis_src[i] = i;
        s->axis_sign[i] = 1;
        s->bias[i] = 0.0;
    }
    for (i = 0; i < 9; i++)
        s->mat[i] = i % 4 == 0 ? 1.0 : 0.0;
}

void rx_config_defaults(rx_config *c)
{
    memset(c, 0, sizeof *c);
    c->baud = 9600;
    c->period = RX_PERIOD_DEFAULT;
    /* 90 deg/s full scale over half of a 12-bit range (CG-L53 + TLC2543) */
    sensor_defaults(&c->gyro, 2048.0, (90.0 * 3.14159265358979323846 / 180.0) / 2048.0);
    sensor_defaults(&c->acc, RX_ACC_ZERO, RX_ACC_SCALE);
    sensor_defaults(&c->mag, RX_MAG_ZERO, RX_MAG_SCALE);
    c->method = ATT_METHOD_RV3;
    att_ahrs_default_settings(&c->ahrs);
    c->estimator = RX_EST_AUTO;
    c->format = RX_FORMAT_CSV;
    c->block_size = 6;
    c->queue_size = 256;
    c->gap_ms = 20;
    c->hold_ms = RX_HOLD_MS_DEFAULT;
    c->reopen_delay = 1.0;
    c->header = 1;
    c->link = RX_LINK_AUTO;
    c->gnss.kind = RX_GNSS_OFF;
}

int rx_rate_check(long baud, unsigned block_size, double period, char *msg, size_t len)
{
    const unsigned per_block = block_size / ATT_BLOCK_SIZE; /* samples per block */
    const unsigned exchange = block_size + 4u;              /* 0xAA, 0xBB, N data, checksum, answer */
    double need, cap;
    if (per_block == 0 || !(period > 0))
        return 0;
    need = 1.0 / period / (double)per_block;        /* blocks/s */
    cap = (double)baud / (10.0 * (double)exchange); /* 10 bit times per byte (8N1) */
    if (need <= cap)
        return 0;
    snprintf(msg, len,
             "a sample every %g s needs %.1f blocks/s (%u-byte blocks, %u sample%s each), but %ld baud "
             "carries at most %.1f (%u bytes of 10 bits per exchange): the board will lose samples",
             period, need, block_size, per_block, per_block == 1u ? "" : "s", baud, cap, exchange);
    return 1;
}

static int fail(char *msg, size_t len, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, len, fmt, ap);
    va_end(ap);
    return code;
}

static int parse_double(const char *s, double *out)
{
    char *end;
    double v;
    errno = 0;
    v = strtod(s, &end);
    if (end == s || *end != '\0' || errno != 0 || !isfinite(v))
        return -1;
    *out = v;
    return 0;
}

static int parse_ulong(const char *s, unsigned long *out)
{
    char *end;
    unsigned long v;
    if (*s == '-' || *s == '\0')
        return -1;
    errno = 0;
    v = strtoul(s, &end, 10);
    if (*end != '\0' || errno != 0)
        return -1;
    *out = v;
    return 0;
}

/* "a" or "a,b,c" -> three doubles */
static int parse_triple(const char *s, double out[3])
{
    char tmp[128];
    char *p, *tok, *save = NULL;
    int n = 0;
    double v[3];
    if (strlen(s) >= sizeof tmp)
        return -1;
    strcpy(tmp, s);
    for (p = tmp; (tok = strtok_r(p, ",", &save)) != NULL; p = NULL) {
        if (n == 3 || parse_double(tok, &v[n]) != 0)
            return -1;
        n++;
    }
    if (n == 1) {
        out[0] = out[1] = out[2] = v[0];
        return 0;
    }
    if (n != 3)
        return -1;
    out[0] = v[0];
    out[1] = v[1];
    out[2] = v[2];
    return 0;
}

/* "x,y,z", "+y,-x,z", "1,0,2" ... : body axis i = sign * channel */
static int parse_axes(const char *s, int src[3], int sign[3])
{
    char tmp[64];
    char *p, *tok, *save = NULL;
    int n = 0, seen = 0;
    int a_src[3], a_sign[3];
    if (strlen(s) >= sizeof tmp)
        return -1;
    strcpy(tmp, s);
    for (p = tmp; (tok = strtok_r(p, ",", &save)) != NULL; p = NULL) {
        int sg = 1, ch;
        if (n == 3)
            return -1;
        while (isspace((unsigned char)*tok))
            tok++;
        if (*tok == '+' || *tok == '-') {
            sg = *tok == '-' ? -1 : 1;
            tok++;
        }
        if (tok[0] == '\0' || tok[1] != '\0')
            return -1;
        switch (tolower((unsigned char)tok[0])) {
        case 'x':
        case '0':
            ch = 0;
            break;
        case 'y':
        case '1':
            ch = 1;
            break;
        case 'z':
        case '2':
            ch = 2;
            break;
        default:
            return -1;
        }
        if (seen & (1 << ch))
            return -1; /* each channel once */
        seen |= 1 << ch;
        a_src[n] = ch;
        a_sign[n] = sg;
        n++;
    }
    if (n != 3)
        return -1;
    memcpy(src, a_src, sizeof a_src);
    memcpy(sign, a_sign, sizeof a_sign);
    return 0;
}

/* "a,b,...": exactly n doubles */
static int parse_list(const char *s, double *out, int n)
{
    char tmp[256];
    char *p, *tok, *save = NULL;
    int k = 0;
    if (strlen(s) >= sizeof tmp)
        return -1;
    strcpy(tmp, s);
    for (p = tmp; (tok = strtok_r(p, ",", &save)) != NULL; p = NULL) {
        if (k == n || parse_double(tok, &out[k]) != 0)
            return -1;
        k++;
    }
    return k == n ? 0 : -1;
}

static double det3(const double m[9])
{
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6])
           + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

/* gyro-*, acc-*, mag-* (and axes): key is the part after the prefix; unit names the scale's unit. */
static int set_sensor(rx_sensor_cfg *s, const char *name, const char *key, const char *value,
                      const char *unit, char *msg, size_t len)
{
    double v[9];
    if (strcmp(key, "zero") == 0) {
        if (parse_triple(value, v) != 0 || v[0] < 0 || v[1] < 0 || v[2] < 0 || v[0] > ATT_SENSOR_ZERO_MAX
            || v[1] > ATT_SENSOR_ZERO_MAX || v[2] > ATT_SENSOR_ZERO_MAX)
            return fail(msg, len, RX_EXIT_CONFIG, "%s: '%s' must be CODE or CODE,CODE,CODE (0..65535)", name,
                        value);
        memcpy(s->zero, v, sizeof s->zero);
    } else if (strcmp(key, "scale") == 0) {
        if (parse_triple(value, v) != 0 || v[0] == 0 || v[1] == 0 || v[2] == 0)
            return fail(msg, len, RX_EXIT_CONFIG, "%s: '%s' must be %s_PER_CODE or three of them, non-zero",
                        name, value, unit);
        memcpy(s->scale, v, sizeof s->scale);
    } else if (strcmp(key, "axes") == 0) {
        if (parse_axes(value, s->axis_src, s->axis_sign) != 0)
            return fail(msg, len, RX_EXIT_CONFIG,
                        "%s: '%s' must name each channel once with an optional sign, e.g. x,y,z or -y,+x,z",
                        name, value);
    } else if (strcmp(key, "matrix") == 0) {
        if (parse_list(value, v, 9) != 0 || !(fabs(det3(v)) * ATT_SENSOR_DET_RECIP >= 1.0))
            return fail(msg, len, RX_EXIT_CONFIG,
                        "%s: '%s' must be 9 numbers (row-major) of an invertible matrix, |det| >= 1/%d", name,
                        value, ATT_SENSOR_DET_RECIP);
        memcpy(s->mat, v, sizeof s->mat);
    } else if (strcmp(key, "bias") == 0) {
        if (parse_triple(value, v) != 0)
            return fail(msg, len, RX_EXIT_CONFIG, "%s: '%s' must be B or B,B,B (%s)", name, value,
                        strcmp(unit, "UT") == 0         ? "uT"
                        : strcmp(unit, "M_PER_S2") == 0 ? "m/s^2"
                                                        : "rad/s");
        memcpy(s->bias, v, sizeof s->bias);
    } else {
        return fail(msg, len, RX_EXIT_CONFIG, "unknown setting '%s'", name);
    }
    return 0;
}

/* A filter setting by its att_ahrs_settings field name. The settings so far pass
 * att_ahrs_check_settings (the defaults do, and each change is checked): a failure
 * is this setting's. */
static int set_ahrs(rx_config *c, const char *name, const char *value, char *msg, size_t len)
{
    att_ahrs_settings t = c->ahrs;
    double d;
    size_t i;
    for (i = 0; i < ATT_AHRS_REAL_SETTINGS; i++)
        if (strcmp(name, att_ahrs_setting_field(i, NULL)) == 0)
            break;
    if (i == ATT_AHRS_REAL_SETTINGS)
        return fail(msg, len, RX_EXIT_CONFIG, "unknown setting '%s'", name);
    if (parse_double(value, &d) != 0)
        return fail(msg, len, RX_EXIT_CONFIG, "%s: '%s' is not a number", name, value);
    *ahrs_field(&t, i) = (att_real)d;
    if (att_ahrs_check_settings(&t) != ATT_OK)
        return fail(msg, len, RX_EXIT_CONFIG,
                    "%s: %s is outside its domain (attitude/ahrs.h: noises and times > 0, '0 = off' fields "
                    ">= 0, |declination| <= pi, |sensor_delay| <= 1 s, |acc_delay|, |mag_delay| <= 0.05 s)",
                    name, value);
    c->ahrs = t;
    return 0;
}

int rx_config_set(rx_config *c, const char *name, const char *value, char *msg, size_t len)
{
    unsigned long u;
    double d;
    size_t i;
    if (value == NULL)
        return fail(msg, len, RX_EXIT_USAGE, "option --%s needs a value", name);
    if (strcmp(name, "port") == 0) {
        if (strlen(value) >= sizeof c->port || value[0] == '\0')
            return fail(msg, len, RX_EXIT_CONFIG, "port: bad path '%s'", value);
        strcpy(c->port, value);
    } else if (strcmp(name, "baud") == 0) {
        if (parse_ulong(value, &u) != 0 || !rx_serial_baud_ok((long)u))
            return fail(msg, len, RX_EXIT_CONFIG, "baud: '%s' is not a supported rate (" RX_BAUDS_TEXT ")",
                        value);
        c->baud = (long)u;
    } else if (strcmp(name, "period") == 0) {
        if (parse_double(value, &d) != 0 || !(d > 0.0) || d > 10.0)
            return fail(msg, len, RX_EXIT_CONFIG,
                        "period: '%s' must be a sample period in seconds, 0 < T <= 10", value);
        c->period = d;
        c->period_set = 1;
    } else if (strncmp(name, "gyro-", 5) == 0 || strcmp(name, "axes") == 0) {
        return set_sensor(&c->gyro, name, strcmp(name, "axes") == 0 ? "axes" : name + 5, value, "RAD_PER_S",
                          msg, len);
    } else if (strncmp(name, "acc-", 4) == 0) {
        return set_sensor(&c->acc, name, name + 4, value, "M_PER_S2", msg, len);
    } else if (strncmp(name, "mag-", 4) == 0) {
        return set_sensor(&c->mag, name, name + 4, value, "UT", msg, len);
    } else if (strcmp(name, "method") == 0) {
        for (i = 0; i < sizeof methods / sizeof methods[0]; i++)
            if (strcmp(value, methods[i].name) == 0)
                break;
        if (i == sizeof methods / sizeof methods[0])
            return fail(msg, len, RX_EXIT_CONFIG,
                        "method: unknown '%s' (rv1, rv2, rv3, rv3-coning, rv3-reuse, rv3-reuse-poly, rk4)",
                        value);
        c->method = methods[i].method;
        c->method_set = 1;
    } else if (strcmp(name, "estimator") == 0) {
        for (i = 0; i < 3 && strcmp(value, rx_estimator_name((rx_estimator)i)) != 0; i++)
            ;
        if (i == 3)
            return fail(msg, len, RX_EXIT_CONFIG, "estimator: '%s' must be auto, ahrs or integrator", value);
        c->estimator = (rx_estimator)i;
    } else if (strcmp(name, "format") == 0) {
        if (strcmp(value, "csv") == 0)
            c->format = RX_FORMAT_CSV;
        else if (strcmp(value, "jsonl") == 0)
            c->format = RX_FORMAT_JSONL;
        else
            return fail(msg, len, RX_EXIT_CONFIG, "format: '%s' must be csv or jsonl", value);
    } else if (strcmp(name, "block-size") == 0) {
        if (parse_ulong(value, &u) != 0 || u == 0 || u % 6 != 0 || u > ATT_LINK_BLOCK_MAX)
            return fail(msg, len, RX_EXIT_CONFIG,
                        "block-size: '%s' must be a multiple of 6 (3 x 16-bit codes per sample) up to 60",
                        value);
        c->block_size = (unsigned)u;
    } else if (strcmp(name, "queue") == 0) {
        if (parse_ulong(value, &u) != 0 || u == 0 || u > RX_QUEUE_MAX)
            return fail(msg, len, RX_EXIT_CONFIG, "queue: '%s' must be 1..%d samples", value, RX_QUEUE_MAX);
        c->queue_size = (unsigned)u;
    } else if (strcmp(name, "gap-ms") == 0) {
        if (parse_ulong(value, &u) != 0 || u == 0 || u > ATT_LINK_TIMEOUT_MAX)
            return fail(msg, len, RX_EXIT_CONFIG, "gap-ms: '%s' must be 1..%d ms", value,
                        ATT_LINK_TIMEOUT_MAX);
        c->gap_ms = (unsigned)u;
    } else if (strcmp(name, "link") == 0) {
        if (strcmp(value, "legacy") == 0)
            c->link = RX_LINK_LEGACY;
        else if (strcmp(value, "v2") == 0)
            c->link = RX_LINK_V2;
        else if (strcmp(value, "auto") == 0)
            c->link = RX_LINK_AUTO;
        else
            return fail(msg, len, RX_EXIT_CONFIG, "link: '%s' must be legacy, v2 or auto", value);
    } else if (strcmp(name, "hold-ms") == 0) {
        if (parse_ulong(value, &u) != 0 || u > RX_HOLD_MS_MAX)
            return fail(msg, len, RX_EXIT_CONFIG, "hold-ms: '%s' must be 0..%d ms", value, RX_HOLD_MS_MAX);
        c->hold_ms = (unsigned)u;
    } else if (strcmp(name, "count") == 0) {
        if (parse_ulong(value, &u) != 0)
            return fail(msg, len, RX_EXIT_CONFIG, "count: '%s' must be a number of output lines", value);
        c->count = u;
    } else if (strcmp(name, "consumer-delay") == 0) {
        if (parse_double(value, &d) != 0 || d < 0 || d > 10)
            return fail(msg, len, RX_EXIT_CONFIG, "consumer-delay: '%s' must be 0..10 s", value);
        c->consumer_delay = d;
    } else if (strcmp(name, "reopen-delay") == 0) {
        if (parse_double(value, &d) != 0 || d < 0.01 || d > 60)
            return fail(msg, len, RX_EXIT_CONFIG, "reopen-delay: '%s' must be 0.01..60 s", value);
        c->reopen_delay = d;
    } else if (strcmp(name, "gnss") == 0) {
        return rx_gnss_parse(value, &c->gnss, msg, len);
    } else if (strcmp(name, "gnss_latency") == 0) {
        if (parse_double(value, &d) != 0 || d < 0 || d > RX_GNSS_LATENCY_MAX)
            return fail(msg, len, RX_EXIT_CONFIG, "gnss_latency: '%s' must be 0..%g s", value,
                        RX_GNSS_LATENCY_MAX);
        c->gnss_latency = d;
    } else if (strcmp(name, "header") == 0) {
        if (strcmp(value, "yes") == 0 || strcmp(value, "1") == 0)
            c->header = 1;
        else if (strcmp(value, "no") == 0 || strcmp(value, "0") == 0)
            c->header = 0;
        else
            return fail(msg, len, RX_EXIT_CONFIG, "header: '%s' must be yes or no", value);
    } else {
        return set_ahrs(c, name, value, msg, len);
    }
    return 0;
}

static char *trim(char *s)
{
    char *e;
    while (isspace((unsigned char)*s))
        s++;
    e = s + strlen(s);
    while (e > s && isspace((unsigned char)e[-1]))
        *--e = '\0';
    return s;
}

int rx_config_file(rx_config *c, const char *path, char *msg, size_t len)
{
    char line[512];
    unsigned lineno = 0;
    FILE *f = fopen(path, "r");
    if (f == NULL)
        return fail(msg, len, RX_EXIT_CONFIG, "config file %s: %s", path, strerror(errno));
    while (fgets(line, sizeof line, f) != NULL) {
        char *hash, *eq, *name, *value;
        int rc;
        lineno++;
        if (strchr(line, '\n') == NULL && !feof(f)) {
            fclose(f);
            return fail(msg, len, RX_EXIT_CONFIG, "%s:%u: line too long", path, lineno);
        }
        if ((hash = strchr(line, '#')) != NULL)
            *hash = '\0';
        name = trim(line);
        if (*name == '\0')
            continue;
        eq = strchr(name, '=');
        if (eq == NULL) {
            fclose(f);
            return fail(msg, len, RX_EXIT_CONFIG, "%s:%u: expected 'name = value'", path, lineno);
        }
        *eq = '\0';
        value = trim(eq + 1);
        name = trim(name);
        if (strcmp(name, "config") == 0) {
            fclose(f);
            return fail(msg, len, RX_EXIT_CONFIG, "%s:%u: config files do not nest", path, lineno);
        }
        rc = rx_config_set(c, name, value, msg, len);
        if (rc != 0) {
            char inner[RX_MSG_MAX];
            snprintf(inner, sizeof inner, "%s", msg);
            fclose(f);
            return fail(msg, len, RX_EXIT_CONFIG, "%s:%u: %s", path, lineno, inner);
        }
    }
    fclose(f);
    return 0;
}

/* Long options: every setting of rx_config_set (same names as in a config
 * file) plus the command-line-only ones. */
enum {
    OPT_HELP = 'h',
    OPT_VERSION = 256,
    OPT_CONFIG,
    OPT_NO_HEADER,
    OPT_SETTING
};

static const struct option long_options[] = { { "help", no_argument, NULL, OPT_HELP },
                                              { "version", no_argument, NULL, OPT_VERSION },
                                              { "config", required_argument, NULL, OPT_CONFIG },
                                              { "no-header", no_argument, NULL, OPT_NO_HEADER },
                                              { "port", required_argument, NULL, OPT_SETTING },
                                              { "link", required_argument, NULL, OPT_SETTING },
                                              { "baud", required_argument, NULL, OPT_SETTING },
                                              { "period", required_argument, NULL, OPT_SETTING },
                                              { "gyro-zero", required_argument, NULL, OPT_SETTING },
                                              { "gyro-scale", required_argument, NULL, OPT_SETTING },
                                              { "axes", required_argument, NULL, OPT_SETTING },
                                              { "method", required_argument, NULL, OPT_SETTING },
                                              { "format", required_argument, NULL, OPT_SETTING },
                                              { "block-size", required_argument, NULL, OPT_SETTING },
                                              { "queue", required_argument, NULL, OPT_SETTING },
                                              { "gap-ms", required_argument, NULL, OPT_SETTING },
                                              { "hold-ms", required_argument, NULL, OPT_SETTING },
                                              { "count", required_argument, NULL, OPT_SETTING },
                                              { "consumer-delay", required_argument, NULL, OPT_SETTING },
                                              { "reopen-delay", required_argument, NULL, OPT_SETTING },
                                              { "header", required_argument, NULL, OPT_SETTING },
                                              { "estimator", required_argument, NULL, OPT_SETTING },
                                              { "acc-zero", required_argument, NULL, OPT_SETTING },
                                              { "acc-scale", required_argument, NULL, OPT_SETTING },
                                              { "acc-axes", required_argument, NULL, OPT_SETTING },
                                              { "acc-matrix", required_argument, NULL, OPT_SETTING },
                                              { "acc-bias", required_argument, NULL, OPT_SETTING },
                                              { "mag-zero", required_argument, NULL, OPT_SETTING },
                                              { "mag-scale", required_argument, NULL, OPT_SETTING },
                                              { "mag-axes", required_argument, NULL, OPT_SETTING },
                                              { "mag-matrix", required_argument, NULL, OPT_SETTING },
                                              { "mag-bias", required_argument, NULL, OPT_SETTING },
                                              { "gyro-matrix", required_argument, NULL, OPT_SETTING },
                                              { "gyro-bias", required_argument, NULL, OPT_SETTING },
                                              { "gnss", required_argument, NULL, OPT_SETTING },
                                              { "gnss_latency", required_argument, NULL, OPT_SETTING } };

enum {
    N_BASE = sizeof long_options / sizeof long_options[0],
    N_AHRS = ATT_AHRS_REAL_SETTINGS
};

/* The options getopt_long sees: the list above, then one per filter setting, then the end. */
static const struct option *all_options(void)
{
    static struct option all[N_BASE + N_AHRS + 1];
    size_t i;
    for (i = 0; i < N_BASE; i++)
        all[i] = long_options[i];
    for (i = 0; i < N_AHRS; i++) {
        all[N_BASE + i].name = att_ahrs_setting_field(i, NULL);
        all[N_BASE + i].has_arg = required_argument;
        all[N_BASE + i].flag = NULL;
        all[N_BASE + i].val = OPT_SETTING;
    }
    memset(&all[N_BASE + N_AHRS], 0, sizeof all[0]);
    return all;
}

/* The option as the user wrote it (argv[optind - 1], without "=value"). */
static const char *opt_text(char **argv, char *buf, size_t len)
{
    const char *a = argv[optind - 1];
    size_t n = strcspn(a, "=");
    if (optopt != 0 && optopt != OPT_HELP && a[0] == '-' && a[1] != '-') { /* -x, or -x inside -abx */
        snprintf(buf, len, "-%c", optopt);
        return buf;
    }
    snprintf(buf, len, "%.*s", (int)(n < len ? n : len - 1), a);
    return buf;
}

/* One getopt_long pass over argv; pass 1 handles -h, --version and
 * --config, pass 2 the settings (so the command line wins over the files). */
static int parse_pass(rx_config *c, int argc, char **argv, int pass, rx_action *action, char *msg, size_t len)
{
    int ch, idx, rc;
    char opt[64];
    const struct option *options = all_options();
    optind = 0; /* full rescan (glibc and musl) */
    opterr = 0; /* messages are ours: one line naming the option */
    for (;;) {
        idx = -1;
        optopt = 0;
        ch = getopt_long(argc, argv, ":h", options, &idx);
        if (ch == -1)
            break;
        switch (ch) {
        case OPT_HELP:
        case OPT_VERSION:
            if (pass == 1) {
                *action = ch == OPT_HELP ? RX_HELP : RX_VERSION_INFO;
                return 0;
            }
            break;
        case OPT_CONFIG:
            if (pass == 1 && (rc = rx_config_file(c, optarg, msg, len)) != 0)
                return rc;
            break;
        case OPT_NO_HEADER:
            c->header = 0;
            break;
        case OPT_SETTING:
            if (pass == 2 && (rc = rx_config_set(c, options[idx].name, optarg, msg, len)) != 0)
                return rc;
            break;
        case ':':
            return fail(msg, len, RX_EXIT_USAGE, "option %s needs a value (see --help)",
                        opt_text(argv, opt, sizeof opt));
        default: /* '?': unknown (or ambiguous abbreviation) */
            return fail(msg, len, RX_EXIT_USAGE, "unknown option %s (see --help)",
                        opt_text(argv, opt, sizeof opt));
        }
    }
    if (optind < argc)
        return fail(msg, len, RX_EXIT_USAGE, "unexpected argument '%s' (options start with --)",
                    argv[optind]);
    return 0;
}

/* The filter integrates with --method when one is given (rk4 is not one it can run:
 * refused with --estimator ahrs; with auto the filter keeps its default). */
static int ahrs_method(rx_config *c, char *msg, size_t len)
{
    if (!c->method_set)
        return 0;
    if (c->method != ATT_METHOD_RK4)
        c->ahrs.method = (int)c->method;
    else if (c->estimator == RX_EST_AHRS)
        return fail(msg, len, RX_EXIT_CONFIG,
                    "method: rk4 cannot run in the filter (--estimator ahrs): choose rv1 .. rv3-reuse-poly");
    return 0;
}

int rx_config_parse(rx_config *c, int argc, char **argv, rx_action *action, char *msg, size_t len)
{
    int rc;
    *action = RX_RUN;
    if ((rc = parse_pass(c, argc, argv, 1, action, msg, len)) != 0 || *action != RX_RUN)
        return rc;
    if ((rc = parse_pass(c, argc, argv, 2, action, msg, len)) != 0)
        return rc;
    if (c->port[0] == '\0')
        return fail(msg, len, RX_EXIT_USAGE,
                    "no serial port: give --port PATH (or port = PATH in --config FILE)");
    return ahrs_method(c, msg, len);
}

/* The filter's settings with their defaults, from the table (attitude/ahrs.h gives units and domains). */
static void usage_ahrs(FILE *f)
{
    att_ahrs_settings d;
    const char *name;
    double v;
    size_t i;
    int col = 0;
    att_ahrs_default_settings(&d);
    fprintf(f,
            "Filter settings (--estimator ahrs), named as the fields of att_ahrs_settings (attitude/ahrs.h:\n"
            "units and domains; docs/ahrs.md), --NAME VALUE or NAME = VALUE; defaults:\n");
    for (i = 0; (name = rx_ahrs_setting(i, &d, &v)) != NULL; i++) {
        char item[64];
        int n = snprintf(item, sizeof item, "%s %g", name, v);
        if (col > 0 && col + n + 2 > 96) {
            fputs(",\n", f);
            col = 0;
        }
        col += fprintf(f, "%s%s", col ? ", " : "  ", item);
    }
    fprintf(f, "\n  method: --method (the filter's default: %s)\n", rx_method_name((att_method)d.method));
}

void rx_usage(const char *prog, void *stream)
{
    fprintf(
        (FILE *)stream,
        "usage: %s --port PATH [options]\n"
        "Receive gyro samples and reports over the serial link (link v2, or the legacy AA/BB\n"
        "handshake with checksum and 00/FF answer: whichever the board speaks; block format of\n"
        "attitude/block.h), integrate the attitude in a second thread, print one line per attitude\n"
        "update (and, with --format jsonl, one record per report).\n\n"
        "  --port PATH              serial device (required)\n"
        "  --baud N                 line rate, default 9600 (8N1 raw)\n"
        "  --period SECONDS         gyro sample period; default: the one the BOOT report announces\n"
        "                           (0.02 s until one arrives); given, it wins over BOOT (warning)\n"
        "  --gyro-zero CODE[,C,C]   ADC code at zero rate, default 2048\n"
        "  --gyro-scale K[,K,K]     rad/s per code, default 7.6699e-4 (90 deg/s per 2048 codes)\n"
        "  --axes A,B,C             body x,y,z from channels with signs, default x,y,z (e.g. -y,x,z)\n"
        "  --method M               rv1|rv2|rv3|rv3-coning|rv3-reuse|rv3-reuse-poly|rk4, default rv3\n"
        "  --format F               csv|jsonl, default csv; --no-header drops the CSV header\n"
        "  --block-size N           legacy link block bytes (multiple of 6), default 6\n"
        "  --queue N                records the inter-thread queue holds, default 256\n"
        "  --gap-ms MS              legacy link gap timeout inside a block, default 20\n"
        "  --link P                 auto (default: the protocol the board speaks, detected from\n"
        "                           its first valid v2 frame or legacy block, which is not lost),\n"
        "                           v2 (link v2) or legacy (AA/BB handshake)\n"
        "  --hold-ms MS             a legacy block that finds the queue full waits this long for\n"
        "                           room before it is answered 0xFF (send again), default 20\n"
        "  --count N                stop after N attitude lines (default: until SIGINT/SIGTERM)\n"
        "  --reopen-delay SECONDS   wait between attempts to reopen a vanished port, default 1\n"
        "  --consumer-delay SECONDS make the attitude thread sleep per record (diagnostics)\n"
        "  --estimator E            auto|ahrs|integrator: the attitude filter (att_ahrs: gyro bias,\n"
        "                           accelerometer and magnetometer aiding) or the gyros alone; auto\n"
        "                           (default): ahrs when the stream's CHANNELS report announces\n"
        "                           accelerometer and magnetometer, else integrator\n"
        "  --acc-zero, --acc-scale, --acc-axes, --acc-matrix, --acc-bias: the accelerometer's codes\n"
        "                           -> m/s^2, as --gyro-zero, --gyro-scale, --axes, then M (v - b):\n"
        "                           9 values row-major (default identity), b in m/s^2 (default 0)\n"
        "  --mag-zero, --mag-scale, --mag-axes, --mag-matrix, --mag-bias: the magnetometer's, in uT\n"
        "                           (matrix: soft iron, bias: hard iron); --gyro-matrix, --gyro-bias\n"
        "  --gnss SOURCE            a GNSS receiver's velocity for the filter (docs/gnss.md): gpsd[:HOST\n"
        "                           [:PORT]] (default localhost:2947; gpsd support: --version says) or\n"
        "                           a serial port PATH[:BAUD] read as NMEA 0183 / UBX NAV-PVT (9600)\n"
        "  --gnss_latency SECONDS   a fix's time of validity to its arrival here, default 0 (0..2)\n"
        "  --config FILE            'name = value' lines with the names above; the command line wins\n"
        "  -h, --help               this text;  --version: the version\n"
        "A block (v2: a record) is acknowledged only once its records are queued; every acknowledged\n"
        "sample is integrated and printed, also on --count and SIGINT/SIGTERM. Missing samples\n"
        "(loss reports, bad codes) are filled by holding the last rate and counted\n"
        "(docs/attitude-rx.md).\n"
        "Exit codes: 0 ok, 64 usage, 66 no such port, 69 gpsd unreachable or not built in,\n"
        "74 port not usable or stdout failed, 75 stopped while stdout stayed blocked\n"
        "(acknowledged samples unprinted), 77 permission denied, 78 bad configuration.\n",
        prog);
    usage_ahrs((FILE *)stream);
}
