/*
 * Tests of the GNSS parser (attitude/gnss.h): the NMEA 0183 standard's
 * example epoch (RMC, VTG, GGA, GSA, the well-known 12:35:19 sentences)
 * merged into one fix by UTC time, every field against its closed form;
 * a NAV-PVT frame built here byte by byte (u-blox offsets and units);
 * bad checksums, overruns, cut sentences, empty fields, skipped UBX
 * messages, NMEA and UBX interleaved, feed_buf, NULLs and a corrupted
 * state. The differential tests against pynmea2 / pyubx2 are in
 * tests/test_gnss.py.
 */
#include <string.h>

#include "att_test.h"
#include "attitude/gnss.h"

#define PI     3.14159265358979323846
#define D2R(d) ((d)*PI / 180.0)
#define KNOT   (1852.0 / 3600.0)

/* f32: 24-bit mantissa, a latitude near 1 rad to ~1e-7, values near 1e3 to ~1e-4 */
#define TOL_ANGLE (sizeof(att_real) == 4 ? 2e-7 : 1e-12)
#define TOL_VAL   (sizeof(att_real) == 4 ? 1e-4 : 1e-9)

static const char *RMC = "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A\r\n";
static const char *VTG = "$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*48\r\n";
static const char *GGA = "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n";
static const char *GSA = "$GPGSA,A,3,04,05,,09,12,,,24,,,,,2.5,1.3,2.1*39\r\n";

/* Feed a string; the number of fixes, the last in *out, each result counted in res[]. */
static int feed_str(att_gnss_parser *p, const char *s, att_gnss_fix *out, int res[5])
{
    int n = 0;
    for (; *s; s++) {
        att_gnss_result r = att_gnss_feed(p, (uint8_t)*s, out);
        CHECK(r >= 0);
        if (r >= 0 && res) {
            res[r]++;
        }
        n += r == ATT_GNSS_FIX;
    }
    return n;
}

/* "$body*hh\r\n" with the checksum computed here. */
static void sentence(char *dst, const char *body)
{
    unsigned x = 0;
    const char *c;
    for (c = body; *c; c++) {
        x ^= (unsigned char)*c;
    }
    sprintf(dst, "$%s*%02X\r\n", body, x);
}

static void test_epoch(void)
{
    att_gnss_parser p;
    att_gnss_fix f;
    char next[100];
    int res[5] = { 0 };
    double lat = D2R(48.0 + 7.038 / 60.0), lon = D2R(11.0 + 31.0 / 60.0);
    CHECK_EQ_INT(att_gnss_init(&p), ATT_OK);
    CHECK_EQ_INT(feed_str(&p, RMC, &f, res) + feed_str(&p, VTG, &f, res), 0);
    CHECK_EQ_INT(feed_str(&p, GGA, &f, res) + feed_str(&p, GSA, &f, res), 0);
    CHECK_EQ_INT(res[ATT_GNSS_MESSAGE], 4);
    sentence(next, "GPRMC,123520,A,4807.038,N,01131.000,E,,,230394,003.1,W");
    CHECK_EQ_INT(feed_str(&p, next, &f, NULL), 1); /* a new time closes the epoch */
    CHECK_EQ_INT(f.sources, ATT_GNSS_SRC_RMC | ATT_GNSS_SRC_VTG | ATT_GNSS_SRC_GGA | ATT_GNSS_SRC_GSA);
    CHECK_CLOSE(f.tod, 12 * 3600 + 35 * 60 + 19, TOL_VAL);
    CHECK(f.year == 1994 && f.month == 3 && f.day == 23);
    CHECK_CLOSE(f.lat, lat, TOL_ANGLE);
    CHECK_CLOSE(f.lon, lon, TOL_ANGLE);
    CHECK_CLOSE(f.height_msl, 545.4, TOL_VAL);
    CHECK_CLOSE(f.height, 545.4 + 46.9, TOL_VAL);
    /* VTG came after RMC: its speed and track win */
    CHECK_CLOSE(f.speed, 5.5 * KNOT, TOL_VAL);
    CHECK_CLOSE(f.track, D2R(54.7), TOL_ANGLE);
    CHECK_CLOSE(f.vel_n, 5.5 * KNOT * cos(D2R(54.7)), TOL_VAL);
    CHECK_CLOSE(f.vel_e, 5.5 * KNOT * sin(D2R(54.7)), TOL_VAL);
    CHECK(!(f.present & ATT_GNSS_HAS_VEL_D) && !(f.present & ATT_GNSS_HAS_TOW)
          && !(f.present & ATT_GNSS_HAS_ACC));
    CHECK_CLOSE(f.hdop, 1.3, TOL_VAL); /* GSA after GGA's 0.9 */
    CHECK_CLOSE(f.pdop, 2.5, TOL_VAL);
    CHECK_CLOSE(f.vdop, 2.1, TOL_VAL);
    CHECK(f.sats == 8 && f.fix_type == ATT_GNSS_FIX_3D && f.valid == 1);
    /* the next epoch: RMC alone, no speed or course */
    CHECK_EQ_INT(att_gnss_flush(&p, &f), ATT_GNSS_FIX);
    CHECK(f.sources == ATT_GNSS_SRC_RMC && !(f.present & (ATT_GNSS_HAS_SPEED | ATT_GNSS_HAS_VEL_NE)));
    CHECK_CLOSE(f.tod, 12 * 3600 + 35 * 60 + 20, TOL_VAL);
    CHECK_EQ_INT(att_gnss_flush(&p, &f), ATT_GNSS_NONE);
    CHECK(p.stats.nmea_accepted == 5 && p.stats.fixes == 2 && p.stats.bad_checksum == 0);
}

static void test_errors(void)
{
    att_gnss_parser p;
    att_gnss_fix f;
    char s[200];
    int i, res[5] = { 0 };
    att_gnss_init(&p);
    feed_str(&p, "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6B\r\n", &f, res);
    CHECK(res[ATT_GNSS_REJECTED] == 1 && p.stats.bad_checksum == 1);
    /* overrun: a body of 77 characters */
    s[0] = '$';
    for (i = 1; i <= 77; i++) {
        s[i] = 'A';
    }
    s[78] = 0;
    feed_str(&p, s, &f, NULL);
    CHECK_EQ_INT(p.stats.overruns, 1);
    /* a body of exactly 76 characters is accepted (ignored: not a known type) */
    sentence(s, "GPXXX,1234567890123456789012345678901234567890123456789012345678901234567890");
    CHECK_EQ_INT(strlen(s), ATT_GNSS_NMEA_MAX);
    feed_str(&p, s, &f, NULL);
    CHECK(p.stats.ignored == 1 && p.stats.overruns == 1);
    /* cut by '$' and by a CR; a bad field; empty fields */
    feed_str(&p, "$GPGGA,1235$GPGGA,12\r\n", &f, NULL);
    CHECK_EQ_INT(p.stats.truncated, 2);
    sentence(s, "GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,5x45.4,M,46.9,M,,");
    feed_str(&p, s, &f, NULL);
    sentence(s, "GPRMC,123519,A,4807.038,N,01131.000,,022.4,084.4,230394,003.1,W"); /* no E/W */
    feed_str(&p, s, &f, NULL);
    CHECK_EQ_INT(p.stats.bad_field, 2);
    sentence(s, "GPRMC,,V,,,,,,,,,,N");
    feed_str(&p, s, &f, NULL);
    CHECK_EQ_INT(att_gnss_flush(&p, &f), ATT_GNSS_FIX);
    CHECK(f.present == ATT_GNSS_HAS_VALID && f.valid == 0);
    CHECK(p.stats.nmea_accepted == 1);
}

/* ---- UBX ---- */

static void put_u(uint8_t *b, unsigned off, unsigned long v, int n)
{
    int i;
    for (i = 0; i < n; i++) {
        b[off + (unsigned)i] = (uint8_t)(v >> (8 * i));
    }
}

/* A UBX frame of class c, id i, payload pl (n bytes) into out; its length. */
static size_t ubx_frame(uint8_t *out, uint8_t c, uint8_t id, const uint8_t *pl, size_t n)
{
    size_t k;
    uint8_t a = 0, b = 0;
    out[0] = 0xB5;
    out[1] = 0x62;
    out[2] = c;
    out[3] = id;
    out[4] = (uint8_t)n;
    out[5] = (uint8_t)(n >> 8);
    memcpy(out + 6, pl, n);
    for (k = 2; k < n + 6; k++) {
        a = (uint8_t)(a + out[k]);
        b = (uint8_t)(b + a);
    }
    out[n + 6] = a;
    out[n + 7] = b;
    return n + 8;
}

static size_t pvt_frame(uint8_t *out)
{
    uint8_t pl[92] = { 0 };
    put_u(pl, 0, 345600250ul, 4); /* iTOW ms */
    put_u(pl, 4, 2026, 2);
    pl[6] = 11;
    pl[7] = 28;
    pl[8] = 20;
    pl[9] = 5;
    pl[10] = 7;
    pl[11] = 0x07;                                /* validDate, validTime, fullyResolved */
    put_u(pl, 16, (unsigned long)-250000000L, 4); /* nano -0.25 s */
    pl[20] = 3;
    pl[21] = 0x01; /* gnssFixOK */
    pl[23] = 14;
    put_u(pl, 24, (unsigned long)-1227000000L, 4); /* lon -122.7 deg */
    put_u(pl, 28, 374000000ul, 4);                 /* lat 37.4 deg */
    put_u(pl, 32, (unsigned long)-12345L, 4);      /* height -12.345 m */
    put_u(pl, 36, 20000ul, 4);
    put_u(pl, 40, 1500ul, 4);
    put_u(pl, 44, 2500ul, 4);
    put_u(pl, 48, 12000ul, 4);
    put_u(pl, 52, (unsigned long)-5000L, 4);
    put_u(pl, 56, 250ul, 4);
    put_u(pl, 60, 13000ul, 4);
    put_u(pl, 64, (unsigned long)-2262000L, 4); /* headMot -22.62 deg */
    put_u(pl, 68, 300ul, 4);
    put_u(pl, 76, 187ul, 2);
    return ubx_frame(out, 0x01, 0x07, pl, 92);
}

static void check_pvt(const att_gnss_fix *f)
{
    CHECK(f->sources == ATT_GNSS_SRC_PVT && f->fix_type == 3 && f->valid == 1 && f->sats == 14);
    CHECK(f->year == 2026 && f->month == 11 && f->day == 28);
    CHECK_CLOSE(f->tow, 345600.25, TOL_VAL * 1e3); /* f32: 345600 to ~0.03 */
    CHECK_CLOSE(f->tod, 20 * 3600 + 5 * 60 + 7 - 0.25, TOL_VAL * 1e2);
    CHECK_CLOSE(f->lat, D2R(37.4), TOL_ANGLE);
    CHECK_CLOSE(f->lon, D2R(-122.7), TOL_ANGLE * 4);
    CHECK_CLOSE(f->height, -12.345, TOL_VAL);
    CHECK_CLOSE(f->height_msl, 20.0, TOL_VAL);
    CHECK_CLOSE(f->vel_n, 12.0, TOL_VAL);
    CHECK_CLOSE(f->vel_e, -5.0, TOL_VAL);
    CHECK_CLOSE(f->vel_d, 0.25, TOL_VAL);
    CHECK_CLOSE(f->speed, 13.0, TOL_VAL);
    CHECK_CLOSE(f->track, D2R(360.0 - 22.62), TOL_ANGLE * 8);
    CHECK_CLOSE(f->h_acc, 1.5, TOL_VAL);
    CHECK_CLOSE(f->v_acc, 2.5, TOL_VAL);
    CHECK_CLOSE(f->s_acc, 0.3, TOL_VAL);
    CHECK_CLOSE(f->pdop, 1.87, TOL_VAL);
}

static int feed_bytes(att_gnss_parser *p, const uint8_t *b, size_t n, att_gnss_fix *out)
{
    size_t i;
    int k = 0;
    for (i = 0; i < n; i++) {
        k += att_gnss_feed(p, b[i], out) == ATT_GNSS_FIX;
    }
    return k;
}

static void test_ubx(void)
{
    att_gnss_parser p;
    att_gnss_fix f;
    uint8_t fr[200], other[40] = { 0 }, big[8] = { 0xB5, 0x62, 0x02, 0x15, 0x01, 0x08, 0, 0 };
    size_t n = pvt_frame(fr), m;
    att_gnss_init(&p);
    CHECK_EQ_INT(feed_bytes(&p, fr, n, &f), 1);
    check_pvt(&f);
    /* another message skipped; a length over the limit; a bad checksum */
    m = ubx_frame(fr + 100, 0x01, 0x35, other, sizeof other);
    CHECK_EQ_INT(feed_bytes(&p, fr + 100, m, &f), 0);
    CHECK_EQ_INT(p.stats.ignored, 1);
    CHECK_EQ_INT(feed_bytes(&p, big, sizeof big, &f), 0);
    CHECK_EQ_INT(p.stats.overruns, 1);
    fr[40] ^= 1;
    CHECK_EQ_INT(feed_bytes(&p, fr, n, &f), 0);
    CHECK_EQ_INT(p.stats.bad_checksum, 1);
    fr[40] ^= 1;
    /* interleaved: a sentence cut by the frame's sync, the frame, then a sentence */
    feed_str(&p, "$GPGGA,123", &f, NULL);
    CHECK_EQ_INT(feed_bytes(&p, fr, n, &f), 1);
    check_pvt(&f);
    CHECK_EQ_INT(feed_str(&p, RMC, &f, NULL), 0);
    CHECK_EQ_INT(att_gnss_flush(&p, &f), ATT_GNSS_FIX);
    CHECK(f.sources == ATT_GNSS_SRC_RMC);
    CHECK(p.stats.truncated == 1 && p.stats.ubx_accepted == 2);
}

static void test_api(void)
{
    att_gnss_parser p, q;
    att_gnss_fix f[4];
    uint8_t fr[200];
    size_t n = pvt_frame(fr), used = 99, k = 99;
    CHECK_EQ_INT(att_gnss_init(NULL), ATT_GNSS_E_NULL);
    att_gnss_init(&p);
    CHECK_EQ_INT(att_gnss_feed(NULL, 0, f), ATT_GNSS_E_NULL);
    CHECK_EQ_INT(att_gnss_feed(&p, 0, NULL), ATT_GNSS_E_NULL);
    CHECK_EQ_INT(att_gnss_flush(&p, NULL), ATT_GNSS_E_NULL);
    CHECK_EQ_INT(att_gnss_feed_buf(&p, NULL, 3, f, 4, &used, &k), ATT_GNSS_E_NULL);
    CHECK_EQ_INT(att_gnss_feed_buf(&p, fr, n, NULL, 4, &used, &k), ATT_GNSS_E_NULL);
    /* two frames, room for one fix: stops right after the first */
    memcpy(fr + n, fr, n);
    CHECK_EQ_INT(att_gnss_feed_buf(&p, fr, 2 * n, f, 1, &used, &k), ATT_OK);
    CHECK(used == n && k == 1);
    CHECK_EQ_INT(att_gnss_feed_buf(&p, fr + used, n, f, 4, &used, &k), ATT_OK);
    CHECK(used == n && k == 1);
    check_pvt(&f[0]);
    q = p;
    q.state = 0xEE;
    CHECK_EQ_INT(att_gnss_feed(&q, '$', f), ATT_GNSS_E_STATE);
    CHECK_EQ_INT(att_gnss_flush(&q, f), ATT_GNSS_E_STATE);
    q = p;
    q.state = 1; /* in a sentence, past its longest body */
    q.len = 500;
    CHECK_EQ_INT(att_gnss_feed(&q, '$', f), ATT_GNSS_E_STATE);
    CHECK(strcmp(att_status_str(ATT_GNSS_E_STATE), "unknown status") != 0);
}

int main(void)
{
    test_epoch();
    test_errors();
    test_ubx();
    test_api();
    return ATT_TEST_REPORT();
}
