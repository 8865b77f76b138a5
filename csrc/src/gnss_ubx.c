/*
 * libattitude — UBX NAV-PVT of the GNSS parser (attitude/gnss.h). Offsets
 * and units: u-blox M8 / M9 receiver description, UBX-NAV-PVT (class 0x01,
 * id 0x07, 92 bytes, little endian).
 */
#include "att_math.h"
#include "gnss_internal.h"

/* Payload offsets (bytes). */
enum {
    PVT_ITOW = 0,     /* U4 ms, GPS time of week */
    PVT_YEAR = 4,     /* U2 */
    PVT_MONTH = 6,    /* U1 */
    PVT_DAY = 7,      /* U1 */
    PVT_HOUR = 8,     /* U1 */
    PVT_MIN = 9,      /* U1 */
    PVT_SEC = 10,     /* U1 */
    PVT_VALID = 11,   /* X1: validDate bit 0, validTime bit 1 */
    PVT_NANO = 16,    /* I4 ns, fraction of the second (-1e9..1e9) */
    PVT_FIX = 20,     /* U1 fixType 0..5 */
    PVT_FLAGS = 21,   /* X1: gnssFixOK bit 0 */
    PVT_NUMSV = 23,   /* U1 */
    PVT_LON = 24,     /* I4 1e-7 deg */
    PVT_LAT = 28,     /* I4 1e-7 deg */
    PVT_HEIGHT = 32,  /* I4 mm above the ellipsoid */
    PVT_HMSL = 36,    /* I4 mm above mean sea level */
    PVT_HACC = 40,    /* U4 mm */
    PVT_VACC = 44,    /* U4 mm */
    PVT_VELN = 48,    /* I4 mm/s */
    PVT_VELE = 52,    /* I4 mm/s */
    PVT_VELD = 56,    /* I4 mm/s */
    PVT_GSPEED = 60,  /* I4 mm/s */
    PVT_HEADMOT = 64, /* I4 1e-5 deg */
    PVT_SACC = 68,    /* U4 mm/s */
    PVT_PDOP = 76,    /* U2 0.01 */
    PVT_FLAGS3 = 78   /* X1: invalidLlh bit 0 */
};

#define MILLI ATT_R(1e-3)

static uint32_t u4(const uint8_t *b, unsigned off)
{
    return (uint32_t)b[off] | (uint32_t)b[off + 1] << 8 | (uint32_t)b[off + 2] << 16
           | (uint32_t)b[off + 3] << 24;
}

/* A two's-complement I4 without implementation-defined conversion. */
static att_real i4(const uint8_t *b, unsigned off)
{
    uint32_t u = u4(b, off);
    return u & 0x80000000u ? -(att_real)(~u) - ATT_R(1.0) : (att_real)u;
}

static void pvt_time(const uint8_t *b, att_gnss_fix *t)
{
    uint8_t valid = b[PVT_VALID];
    t->tow = (att_real)u4(b, PVT_ITOW) * MILLI;
    t->present |= ATT_GNSS_HAS_TOW;
    if (valid & 1u) {
        t->year = (uint16_t)(b[PVT_YEAR] | b[PVT_YEAR + 1] << 8);
        t->month = b[PVT_MONTH];
        t->day = b[PVT_DAY];
        t->present |= ATT_GNSS_HAS_DATE;
    }
    if (valid & 2u) {
        att_real tod =
            (att_real)(b[PVT_HOUR] * 3600u + b[PVT_MIN] * 60u + b[PVT_SEC]) + i4(b, PVT_NANO) * ATT_R(1e-9);
        t->tod = tod < ATT_R(0.0) ? tod + ATT_R(86400.0) : tod; /* nano < 0 at 00:00:00 */
        t->present |= ATT_GNSS_HAS_TOD;
    }
}

/* Fields out of the spec's domain: the frame is rejected. */
static int pvt_bad(const uint8_t *b)
{
    att_real lat = i4(b, PVT_LAT), lon = i4(b, PVT_LON), nano = i4(b, PVT_NANO), head = i4(b, PVT_HEADMOT);
    uint8_t valid = b[PVT_VALID];
    return b[PVT_FIX] > (uint8_t)ATT_GNSS_FIX_TIME || lat > ATT_R(9e8) || lat < ATT_R(-9e8)
           || lon > ATT_R(1.8e9) || lon < ATT_R(-1.8e9) || i4(b, PVT_GSPEED) < ATT_R(0.0) || nano > ATT_R(1e9)
           || nano < ATT_R(-1e9) || head > ATT_R(3.6e7) || head < ATT_R(-3.6e7)
           || ((valid & 1u)
               && (b[PVT_MONTH] < 1u || b[PVT_MONTH] > 12u || b[PVT_DAY] < 1u || b[PVT_DAY] > 31u))
           || ((valid & 2u) && (b[PVT_HOUR] > 23u || b[PVT_MIN] > 59u || b[PVT_SEC] > 60u));
}

att_gnss_result att__gnss_nav_pvt(att_gnss_parser *p, att_gnss_fix *out)
{
    static const att_gnss_fix zero = { 0 };
    const uint8_t *b = p->buf;
    att_gnss_fix t = zero;
    if (pvt_bad(b)) {
        p->stats.bad_field++;
        return ATT_GNSS_REJECTED;
    }
    pvt_time(b, &t);
    t.fix_type = b[PVT_FIX];
    t.valid = (uint8_t)(b[PVT_FLAGS] & 1u);
    t.sats = b[PVT_NUMSV];
    t.present |= ATT_GNSS_HAS_FIX_TYPE | ATT_GNSS_HAS_VALID | ATT_GNSS_HAS_SATS;
    if (!(b[PVT_FLAGS3] & 1u)) { /* invalidLlh clear */
        t.lat = att__gnss_deg_to_rad(i4(b, PVT_LAT) * ATT_R(1e-7));
        t.lon = att__gnss_deg_to_rad(i4(b, PVT_LON) * ATT_R(1e-7));
        t.height = i4(b, PVT_HEIGHT) * MILLI;
        t.height_msl = i4(b, PVT_HMSL) * MILLI;
        t.present |= ATT_GNSS_HAS_LATLON | ATT_GNSS_HAS_HEIGHT | ATT_GNSS_HAS_HEIGHT_MSL;
    }
    t.vel_n = i4(b, PVT_VELN) * MILLI;
    t.vel_e = i4(b, PVT_VELE) * MILLI;
    t.vel_d = i4(b, PVT_VELD) * MILLI;
    t.speed = i4(b, PVT_GSPEED) * MILLI;
    t.track = att__gnss_wrap_2pi(att__gnss_deg_to_rad(i4(b, PVT_HEADMOT) * ATT_R(1e-5)));
    t.h_acc = (att_real)u4(b, PVT_HACC) * MILLI;
    t.v_acc = (att_real)u4(b, PVT_VACC) * MILLI;
    t.s_acc = (att_real)u4(b, PVT_SACC) * MILLI;
    t.pdop = (att_real)(b[PVT_PDOP] | b[PVT_PDOP + 1] << 8) * ATT_R(0.01);
    t.present |= ATT_GNSS_HAS_VEL_NE | ATT_GNSS_HAS_VEL_D | ATT_GNSS_HAS_SPEED | ATT_GNSS_HAS_TRACK
                 | ATT_GNSS_HAS_ACC | ATT_GNSS_HAS_PDOP;
    t.sources = ATT_GNSS_SRC_PVT;
    *out = t;
    p->stats.ubx_accepted++;
    p->stats.fixes++;
    return ATT_GNSS_FIX;
}
