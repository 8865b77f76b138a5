/*
 * libattitude — NMEA 0183 sentences of the GNSS parser (attitude/gnss.h):
 * RMC, VTG, GGA, GSA from any talker, read field by field with integer
 * arithmetic (no strtod, no locale), merged into epochs by UTC time.
 */
#include "att_math.h"
#include "gnss_internal.h"

enum {
    MAX_FIELDS = 24, /* GSA has 19 with its system id; more are ignored */
    MAX_INT = 9,     /* digits before the point (fits uint32) */
    MAX_FRAC = 9     /* digits after the point kept (more are read and dropped) */
};

#define KNOT    ATT_R(1852.0 / 3600.0) /* m/s per knot (1 nmi = 1852 m) */
#define KMH     ATT_R(1.0 / 3.6)       /* m/s per km/h */
#define DAY_SEC 86400u

static const att_real POW10[MAX_FRAC + 1] = { ATT_R(1e0), ATT_R(1e1), ATT_R(1e2), ATT_R(1e3), ATT_R(1e4),
                                              ATT_R(1e5), ATT_R(1e6), ATT_R(1e7), ATT_R(1e8), ATT_R(1e9) };
static const uint32_t NS_SCALE[MAX_FRAC + 1] = { 1000000000u, 100000000u, 10000000u, 1000000u, 100000u,
                                                 10000u,      1000u,      100u,      10u,      1u };

typedef struct {
    const uint8_t *s;
    uint8_t n;
} field;

typedef struct {
    field f[MAX_FIELDS];
    uint8_t count;
} fields;

/* A decimal field: value = (neg ? -1 : 1) * (ip + frac / 10^digits). */
typedef struct {
    uint32_t ip, frac;
    uint8_t digits, neg;
} dec;

/* What one sentence gave: its fields in a fix, and its time. */
typedef struct {
    att_gnss_fix t;
    uint32_t sec, ns; /* hhmmss and the fraction (ns), when t.present has ATT_GNSS_HAS_TOD */
} sentence;

enum {
    F_EMPTY = 0,
    F_OK = 1,
    F_BAD = -1
};

static void split(const uint8_t *buf, uint16_t len, fields *fs)
{
    uint16_t i, start = 0;
    fs->count = 0;
    for (i = 0; i <= len && fs->count < MAX_FIELDS; i++) {
        if (i == len || buf[i] == ',') {
            fs->f[fs->count].s = buf + start;
            fs->f[fs->count].n = (uint8_t)(i - start);
            fs->count++;
            start = (uint16_t)(i + 1);
        }
    }
}

static field get(const fields *fs, uint8_t i)
{
    field none = { 0, 0 };
    return i < fs->count ? fs->f[i] : none;
}

/* The one character of a field, 0 when empty, '?' when longer. */
static uint8_t letter(field f)
{
    return f.n == 0 ? 0 : f.n == 1 ? f.s[0] : (uint8_t)'?';
}

static int parse_dec(field f, dec *d)
{
    uint8_t i = 0, n_int = 0, point = 0;
    d->ip = d->frac = 0;
    d->digits = d->neg = 0;
    if (f.n == 0) {
        return F_EMPTY;
    }
    if (f.s[0] == '-') {
        d->neg = 1;
        i = 1;
    }
    for (; i < f.n; i++) {
        uint8_t c = f.s[i];
        if (c == '.' && !point) {
            point = 1;
        } else if (c < '0' || c > '9') {
            return F_BAD;
        } else if (!point) {
            if (++n_int > MAX_INT) {
                return F_BAD;
            }
            d->ip = d->ip * 10u + (uint32_t)(c - '0');
        } else if (d->digits < MAX_FRAC) {
            d->frac = d->frac * 10u + (uint32_t)(c - '0');
            d->digits++;
        }
    }
    return (n_int + d->digits > 0) ? F_OK : F_BAD;
}

static att_real dec_real(const dec *d)
{
    att_real v = (att_real)d->ip + (att_real)d->frac / POW10[d->digits];
    return d->neg ? -v : v;
}

/* A non-negative number into *v; F_OK, F_EMPTY or F_BAD. */
static int get_real(field f, att_real *v)
{
    dec d;
    int r = parse_dec(f, &d);
    if (r == F_OK) {
        if (d.neg) {
            return F_BAD;
        }
        *v = dec_real(&d);
    }
    return r;
}

/* hhmmss.sss: time of day and its exact key. */
static int get_time(field f, sentence *s)
{
    dec d;
    int r = parse_dec(f, &d);
    uint32_t h, m, sec;
    if (r != F_OK) {
        return r;
    }
    h = d.ip / 10000u;
    m = d.ip / 100u % 100u;
    sec = d.ip % 100u;
    if (d.neg || h > 23u || m > 59u || sec > 60u) {
        return F_BAD;
    }
    s->t.tod = (att_real)(h * 3600u + m * 60u + sec) + (att_real)d.frac / POW10[d.digits];
    s->sec = d.ip;
    s->ns = d.frac * NS_SCALE[d.digits];
    s->t.present |= ATT_GNSS_HAS_TOD;
    return F_OK;
}

/* (d)ddmm.mmm and its hemisphere letter (pos / neg) -> rad; max_deg 90 or 180. */
static int get_angle(field f, field hemi, uint8_t pos, uint8_t neg, uint32_t max_deg, att_real *v)
{
    dec d;
    int r = parse_dec(f, &d);
    uint8_t h = letter(hemi);
    att_real deg;
    if (r != F_OK) {
        return r == F_EMPTY && hemi.n == 0 ? F_EMPTY : F_BAD;
    }
    if (d.neg || d.ip % 100u >= 60u || d.ip / 100u > max_deg || (h != pos && h != neg)) {
        return F_BAD;
    }
    deg = (att_real)(d.ip / 100u)
          + ((att_real)(d.ip % 100u) + (att_real)d.frac / POW10[d.digits]) / ATT_R(60.0);
    if (deg > (att_real)max_deg) {
        return F_BAD;
    }
    *v = att__gnss_deg_to_rad(h == neg ? -deg : deg);
    return F_OK;
}

/* Both latitude and longitude (fields i..i+3), or neither. */
static int get_latlon(const fields *fs, uint8_t i, att_gnss_fix *t)
{
    int a = get_angle(get(fs, i), get(fs, (uint8_t)(i + 1)), 'N', 'S', 90u, &t->lat);
    int b = get_angle(get(fs, (uint8_t)(i + 2)), get(fs, (uint8_t)(i + 3)), 'E', 'W', 180u, &t->lon);
    if (a == F_BAD || b == F_BAD || a != b) {
        return F_BAD;
    }
    if (a == F_OK) {
        t->present |= ATT_GNSS_HAS_LATLON;
    }
    return F_OK;
}

/* A quantity into *v and its bit when given; F_BAD passes through. */
static int opt_real(field f, att_real *v, att_real scale, uint32_t bit, att_gnss_fix *t)
{
    int r = get_real(f, v);
    if (r == F_OK) {
        *v *= scale;
        t->present |= bit;
    }
    return r;
}

static int get_track(field f, att_gnss_fix *t)
{
    int r = opt_real(f, &t->track, ATT_R(1.0), ATT_GNSS_HAS_TRACK, t);
    if (r == F_OK) {
        if (t->track > ATT_R(360.0)) {
            return F_BAD;
        }
        t->track = att__gnss_wrap_2pi(att__gnss_deg_to_rad(t->track));
    }
    return r;
}

static void set_valid(att_gnss_fix *t, int valid)
{
    t->valid = (uint8_t)valid;
    t->present |= ATT_GNSS_HAS_VALID;
}

static void set_fix_type(att_gnss_fix *t, att_gnss_fix_type ft)
{
    t->fix_type = (uint8_t)ft;
    t->present |= ATT_GNSS_HAS_FIX_TYPE;
}

/* ddmmyy -> year, month, day: yy 80..99 -> 19yy (GPS time starts in 1980), 00..79 -> 20yy. */
static int get_date(field f, att_gnss_fix *t)
{
    dec d;
    int r = parse_dec(f, &d);
    uint32_t dd, mm;
    if (r != F_OK) {
        return r;
    }
    dd = d.ip / 10000u;
    mm = d.ip / 100u % 100u;
    if (d.neg || d.digits > 0 || f.n != 6 || dd < 1u || dd > 31u || mm < 1u || mm > 12u) {
        return F_BAD;
    }
    t->day = (uint8_t)dd;
    t->month = (uint8_t)mm;
    t->year = (uint16_t)(d.ip % 100u + (d.ip % 100u >= 80u ? 1900u : 2000u));
    t->present |= ATT_GNSS_HAS_DATE;
    return F_OK;
}

/* RMC: time, status, lat, N/S, lon, E/W, speed (kn), course, date, magvar, E/W, mode. */
static int rmc(const fields *fs, sentence *s)
{
    att_gnss_fix *t = &s->t;
    uint8_t status = letter(get(fs, 2)), mode = letter(get(fs, 12));
    if (get_time(get(fs, 1), s) == F_BAD || get_latlon(fs, 3, t) == F_BAD
        || opt_real(get(fs, 7), &t->speed, KNOT, ATT_GNSS_HAS_SPEED, t) == F_BAD
        || get_track(get(fs, 8), t) == F_BAD || get_date(get(fs, 9), t) == F_BAD
        || (status != 'A' && status != 'V')) {
        return F_BAD;
    }
    set_valid(t, status == 'A' && mode != 'N');
    if (mode == 'E') {
        set_fix_type(t, ATT_GNSS_FIX_DR);
    }
    t->sources = ATT_GNSS_SRC_RMC;
    return F_OK;
}

/* VTG (NMEA 2.3+): course T, 'T', course M, 'M', speed kn, 'N', speed km/h, 'K', mode. */
static int vtg(const fields *fs, sentence *s)
{
    att_gnss_fix *t = &s->t;
    uint8_t mode = letter(get(fs, 9));
    int kn;
    if (get_track(get(fs, 1), t) == F_BAD || letter(get(fs, 2)) != 'T') {
        return F_BAD;
    }
    kn = opt_real(get(fs, 5), &t->speed, KNOT, ATT_GNSS_HAS_SPEED, t);
    if (kn == F_BAD
        || (kn == F_EMPTY && opt_real(get(fs, 7), &t->speed, KMH, ATT_GNSS_HAS_SPEED, t) == F_BAD)) {
        return F_BAD;
    }
    if (mode == 'N') {
        set_valid(t, 0);
    }
    t->sources = ATT_GNSS_SRC_VTG;
    return F_OK;
}

/* GGA: time, lat, N/S, lon, E/W, quality, sats, HDOP, alt, 'M', geoid separation, 'M'. */
static int gga(const fields *fs, sentence *s)
{
    att_gnss_fix *t = &s->t;
    att_real q = 0, sats = 0;
    dec sep;
    int rq, r;
    if (get_time(get(fs, 1), s) == F_BAD || get_latlon(fs, 2, t) == F_BAD
        || (rq = get_real(get(fs, 6), &q)) == F_BAD || q > ATT_R(9.0) || get_real(get(fs, 7), &sats) == F_BAD
        || sats > ATT_R(ATT_GNSS_MAX_SATS)
        || opt_real(get(fs, 8), &t->hdop, ATT_R(1.0), ATT_GNSS_HAS_HDOP, t) == F_BAD) {
        return F_BAD;
    }
    if ((r = parse_dec(get(fs, 9), &sep)) == F_BAD) {
        return F_BAD;
    }
    if (r == F_OK) {
        t->height_msl = dec_real(&sep);
        t->present |= ATT_GNSS_HAS_HEIGHT_MSL;
        if ((r = parse_dec(get(fs, 11), &sep)) == F_BAD) {
            return F_BAD;
        }
        if (r == F_OK) {
            t->height = t->height_msl + dec_real(&sep);
            t->present |= ATT_GNSS_HAS_HEIGHT;
        }
    }
    if (get(fs, 7).n > 0) {
        t->sats = (uint8_t)sats;
        t->present |= ATT_GNSS_HAS_SATS;
    }
    if (rq == F_OK) {
        set_valid(t, q > ATT_R(0.0));
        if (q == ATT_R(0.0) || q == ATT_R(6.0)) {
            set_fix_type(t, q == ATT_R(0.0) ? ATT_GNSS_FIX_NONE : ATT_GNSS_FIX_DR);
        }
    }
    t->sources = ATT_GNSS_SRC_GGA;
    return F_OK;
}

/* GSA: mode A/M, fix 1/2/3, 12 satellite ids, PDOP, HDOP, VDOP[, system id]. */
static int gsa(const fields *fs, sentence *s)
{
    static const att_gnss_fix_type TYPES[3] = { ATT_GNSS_FIX_NONE, ATT_GNSS_FIX_2D, ATT_GNSS_FIX_3D };
    att_gnss_fix *t = &s->t;
    uint8_t ft = letter(get(fs, 2));
    if ((ft != 0 && (ft < '1' || ft > '3'))
        || opt_real(get(fs, 15), &t->pdop, ATT_R(1.0), ATT_GNSS_HAS_PDOP, t) == F_BAD
        || opt_real(get(fs, 16), &t->hdop, ATT_R(1.0), ATT_GNSS_HAS_HDOP, t) == F_BAD
        || opt_real(get(fs, 17), &t->vdop, ATT_R(1.0), ATT_GNSS_HAS_VDOP, t) == F_BAD) {
        return F_BAD;
    }
    if (ft != 0) {
        set_fix_type(t, TYPES[ft - '1']);
    }
    t->sources = ATT_GNSS_SRC_GSA;
    return F_OK;
}

/* The sentence's parser by its type (buf[2..4]), NULL for another type. */
static int (*parser_for(const fields *fs))(const fields *, sentence *)
{
    static const char NAMES[4][4] = { "RMC", "VTG", "GGA", "GSA" };
    static int (*const FNS[4])(const fields *, sentence *) = { rmc, vtg, gga, gsa };
    field f0 = get(fs, 0);
    unsigned i;
    if (f0.n != 5 || f0.s[0] < 'A' || f0.s[0] > 'Z' || f0.s[1] < 'A' || f0.s[1] > 'Z') {
        return 0;
    }
    for (i = 0; i < 4u; i++) {
        if (f0.s[2] == NAMES[i][0] && f0.s[3] == NAMES[i][1] && f0.s[4] == NAMES[i][2]) {
            return FNS[i];
        }
    }
    return 0;
}

/* Copy the quantities s gives into the epoch e (a later sentence wins). */
static void merge(att_gnss_fix *e, const att_gnss_fix *t)
{
    uint32_t has = t->present;
    e->tod = (has & ATT_GNSS_HAS_TOD) ? t->tod : e->tod;
    if (has & ATT_GNSS_HAS_DATE) {
        e->year = t->year;
        e->month = t->month;
        e->day = t->day;
    }
    e->fix_type = (has & ATT_GNSS_HAS_FIX_TYPE) ? t->fix_type : e->fix_type;
    e->valid = (uint8_t)((has & ATT_GNSS_HAS_VALID)
                             ? (t->valid && ((e->present & ATT_GNSS_HAS_VALID) ? e->valid : 1))
                             : e->valid);
    if (has & ATT_GNSS_HAS_LATLON) {
        e->lat = t->lat;
        e->lon = t->lon;
    }
    e->height = (has & ATT_GNSS_HAS_HEIGHT) ? t->height : e->height;
    e->height_msl = (has & ATT_GNSS_HAS_HEIGHT_MSL) ? t->height_msl : e->height_msl;
    e->speed = (has & ATT_GNSS_HAS_SPEED) ? t->speed : e->speed;
    e->track = (has & ATT_GNSS_HAS_TRACK) ? t->track : e->track;
    e->hdop = (has & ATT_GNSS_HAS_HDOP) ? t->hdop : e->hdop;
    e->pdop = (has & ATT_GNSS_HAS_PDOP) ? t->pdop : e->pdop;
    e->vdop = (has & ATT_GNSS_HAS_VDOP) ? t->vdop : e->vdop;
    e->sats = (has & ATT_GNSS_HAS_SATS) ? t->sats : e->sats;
    e->present |= has;
    e->sources = (uint8_t)(e->sources | t->sources);
}

void att__gnss_close_epoch(att_gnss_parser *p, att_gnss_fix *out)
{
    att_gnss_fix *e = &p->epoch;
    if ((e->present & ATT_GNSS_HAS_SPEED) && (e->present & ATT_GNSS_HAS_TRACK)) {
        e->vel_n = e->speed * att_cos(e->track);
        e->vel_e = e->speed * att_sin(e->track);
        e->present |= ATT_GNSS_HAS_VEL_NE;
    } else if ((e->present & ATT_GNSS_HAS_SPEED) && e->speed == ATT_R(0.0)) { /* standing: no course */
        e->vel_n = e->vel_e = ATT_R(0.0);
        e->present |= ATT_GNSS_HAS_VEL_NE;
    }
    *out = *e;
    p->epoch_open = 0;
    p->stats.fixes++;
}

/* A timed sentence of another epoch closes the open one (into *out: 1). */
static int next_epoch(att_gnss_parser *p, const sentence *s, att_gnss_fix *out)
{
    static const att_gnss_fix zero = { 0 };
    int closed = 0;
    int timed = (s->t.present & ATT_GNSS_HAS_TOD) != 0;
    if (timed && (p->epoch_open & ATT__GNSS_TIMED) && (s->sec != p->epoch_sec || s->ns != p->epoch_ns)) {
        att__gnss_close_epoch(p, out);
        closed = 1;
    }
    if (!(p->epoch_open & ATT__GNSS_OPEN)) {
        p->epoch = zero;
        p->epoch_open = ATT__GNSS_OPEN;
    }
    if (timed && !(p->epoch_open & ATT__GNSS_TIMED)) {
        p->epoch_sec = s->sec;
        p->epoch_ns = s->ns;
        p->epoch_open |= ATT__GNSS_TIMED;
    }
    return closed;
}

att_gnss_result att__gnss_nmea(att_gnss_parser *p, att_gnss_fix *out)
{
    static const sentence zero = { { 0 }, 0, 0 };
    fields fs;
    sentence s = zero;
    int (*fn)(const fields *, sentence *);
    int closed;
    split(p->buf, p->len, &fs);
    fn = parser_for(&fs);
    if (fn == 0) {
        p->stats.ignored++;
        return ATT_GNSS_IGNORED;
    }
    if (fn(&fs, &s) != F_OK) {
        p->stats.bad_field++;
        return ATT_GNSS_REJECTED;
    }
    closed = next_epoch(p, &s, out);
    merge(&p->epoch, &s.t);
    p->stats.nmea_accepted++;
    return closed ? ATT_GNSS_FIX : ATT_GNSS_MESSAGE;
}

att_real att__gnss_deg_to_rad(att_real deg)
{
    return deg * (ATT_PI / ATT_R(180.0));
}

att_real att__gnss_wrap_2pi(att_real a)
{
    if (a < ATT_R(0.0)) {
        a += ATT_TWO_PI;
    }
    return a >= ATT_TWO_PI ? a - ATT_TWO_PI : a;
}
