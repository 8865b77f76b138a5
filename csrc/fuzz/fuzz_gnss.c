/*
 * libFuzzer target for the GNSS parser (attitude/gnss.h), built with
 * AddressSanitizer + UndefinedBehaviorSanitizer (`invoke fuzz`).
 *
 * Input: a mode byte, then the stream. Mode bit 0 set: before feeding,
 * every "$...*hh" of the stream gets its correct checksum written and every
 * UBX frame (0xB5 0x62 class id length payload) its Fletcher checksum, so
 * the fuzzer reaches the field parsers and NAV-PVT's decoding rather than
 * the checksum tests only. Mode bit 1 set: the stream is fed through
 * att_gnss_feed_buf with room for (mode >> 2) % 4 + 1 fixes at a time.
 * Mode bit 4 set: the stream is a template (the NMEA standard's example
 * epoch, two NAV-PVT frames, another epoch) edited by the input, read as
 * (position, value) pairs: every field parser is reached at once.
 *
 * Oracles (abort() on a violation):
 *  - no call returns an error; att_gnss_feed_buf gives the same fixes as
 *    att_gnss_feed byte by byte on a second parser, and the same counters;
 *  - every fix: present quantities finite and in their documented domain
 *    (latitude, longitude, track, times, speeds, DOPs, date), absent ones 0,
 *    at least one source; the counters add up (bytes fed, fixes reported);
 *  - never stuck: after the input, ATT_GNSS_UBX_SKIP_MAX + 8 zero bytes and a
 *    valid GGA sentence, flush reports that sentence's fix;
 *  - the documented errors: NULL pointers, a corrupted state.
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "attitude/gnss.h"
#include "fuzz_harness.h"

enum {
    MAX_IN = 4096,
    TEMPLATE_MAX = 4 * 72 * 2 + 2 * 100 /* two epochs of four sentences, two NAV-PVT */
};

static const char GOOD[] = "$GNGGA,235959.50,0130.000,S,10300.000,W,1,07,1.1,-10.5,M,2.0,M,,*";

static void fix_checksums(uint8_t *s, size_t n);

static const char TEMPLATE_NMEA[] = "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A\r\n"
                                    "$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*48\r\n"
                                    "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n"
                                    "$GPGSA,A,3,04,05,,09,12,,,24,,,,,2.5,1.3,2.1*39\r\n";

/* A NAV-PVT frame (checksum left to fix_checksums) at s; its length. */
static size_t pvt_template(uint8_t *s)
{
    static const uint8_t HEAD[6] = { 0xB5, 0x62, 0x01, 0x07, 92, 0 };
    static const uint8_t SOME[24] = { 0x10, 0x27, 0, 0, 0xEA, 0x07, 11,   28,   20, 5,    7, 0x07,
                                      0,    0,    0, 0, 0x00, 0x65, 0xCD, 0x1D, 3,  0x01, 0, 14 };
    memcpy(s, HEAD, sizeof HEAD);
    memset(s + 6, 0x01, 94); /* 0x01010101 fits every I4 field's domain */
    memcpy(s + 6, SOME, sizeof SOME);
    s[6 + 78] = 0; /* flags3: position valid */
    return 100;
}

/* The template stream edited by (position, value) pairs of data[0..n-1]; its length. */
static size_t from_template(uint8_t *s, const uint8_t *data, size_t n)
{
    size_t len = sizeof TEMPLATE_NMEA - 1, i;
    memcpy(s, TEMPLATE_NMEA, len);
    len += pvt_template(s + len);
    len += pvt_template(s + len);
    memcpy(s + len, TEMPLATE_NMEA, sizeof TEMPLATE_NMEA - 1);
    s[len + 11] = '2'; /* RMC and GGA at 12:35:29: the next epoch */
    s[len + 124] = '2';
    len += sizeof TEMPLATE_NMEA - 1;
    fix_checksums(s, len);
    for (i = 0; i + 1 < n; i += 2) {
        s[((size_t)data[i] * 7u + i) % len] = data[i + 1];
    }
    return len;
}

/* Write the checksums a well-formed stream would carry into s (n bytes). */
static void fix_checksums(uint8_t *s, size_t n)
{
    static const char HEX[] = "0123456789ABCDEF";
    size_t i, j;
    for (i = 0; i < n; i++) {
        if (s[i] == '$') {
            uint8_t x = 0;
            for (j = i + 1; j < n && s[j] != '*' && s[j] != '$'; j++) {
                x ^= s[j];
            }
            if (j + 2 < n && s[j] == '*') {
                s[j + 1] = (uint8_t)HEX[x >> 4];
                s[j + 2] = (uint8_t)HEX[x & 15];
            }
        } else if (s[i] == 0xB5 && i + 6 <= n && s[i + 1] == 0x62) {
            size_t len = (size_t)(s[i + 4] | s[i + 5] << 8), k;
            uint8_t a = 0, b = 0;
            if (i + 8 + len <= n) {
                for (k = i + 2; k < i + 6 + len; k++) {
                    a = (uint8_t)(a + s[k]);
                    b = (uint8_t)(b + a);
                }
                s[i + 6 + len] = a;
                s[i + 7 + len] = b;
            }
        }
    }
}

static int in(att_real v, double lo, double hi)
{
    return isfinite(v) && v >= lo && v <= hi;
}

/* A fix's present quantities in their domain, absent ones 0. */
static void check_fix(const att_gnss_fix *f)
{
    static const struct {
        uint32_t bit;
        size_t off;
        double lo, hi;
    } R[] = {
        { ATT_GNSS_HAS_TOD, offsetof(att_gnss_fix, tod), 0.0, 86401.0 },
        { ATT_GNSS_HAS_TOW, offsetof(att_gnss_fix, tow), 0.0, 4294967.296 },
        { ATT_GNSS_HAS_LATLON, offsetof(att_gnss_fix, lat), -1.5707964, 1.5707964 },
        { ATT_GNSS_HAS_LATLON, offsetof(att_gnss_fix, lon), -3.1415927, 3.1415927 },
        { ATT_GNSS_HAS_HEIGHT, offsetof(att_gnss_fix, height), -4.3e9, 4.3e9 },
        { ATT_GNSS_HAS_HEIGHT_MSL, offsetof(att_gnss_fix, height_msl), -1e9, 1e9 },
        { ATT_GNSS_HAS_VEL_NE, offsetof(att_gnss_fix, vel_n), -1e9, 1e9 },
        { ATT_GNSS_HAS_VEL_NE, offsetof(att_gnss_fix, vel_e), -1e9, 1e9 },
        { ATT_GNSS_HAS_VEL_D, offsetof(att_gnss_fix, vel_d), -2.2e6, 2.2e6 },
        { ATT_GNSS_HAS_SPEED, offsetof(att_gnss_fix, speed), 0.0, 1e9 },
        { ATT_GNSS_HAS_TRACK, offsetof(att_gnss_fix, track), 0.0, 6.2831854 },
        { ATT_GNSS_HAS_HDOP, offsetof(att_gnss_fix, hdop), 0.0, 1e10 },
        { ATT_GNSS_HAS_PDOP, offsetof(att_gnss_fix, pdop), 0.0, 1e10 },
        { ATT_GNSS_HAS_VDOP, offsetof(att_gnss_fix, vdop), 0.0, 1e10 },
        { ATT_GNSS_HAS_ACC, offsetof(att_gnss_fix, h_acc), 0.0, 4.3e6 },
        { ATT_GNSS_HAS_ACC, offsetof(att_gnss_fix, v_acc), 0.0, 4.3e6 },
        { ATT_GNSS_HAS_ACC, offsetof(att_gnss_fix, s_acc), 0.0, 4.3e6 },
    };
    size_t i;
    for (i = 0; i < sizeof R / sizeof R[0]; i++) {
        att_real v;
        memcpy(&v, (const uint8_t *)f + R[i].off, sizeof v);
        FUZZ_CHECK((f->present & R[i].bit) ? in(v, R[i].lo, R[i].hi) : v == 0);
    }
    FUZZ_CHECK(!(f->present & ATT_GNSS_HAS_DATE)
               || (f->month >= 1 && f->month <= 12 && f->day >= 1 && f->day <= 31));
    FUZZ_CHECK(!(f->present & ATT_GNSS_HAS_FIX_TYPE) || f->fix_type <= ATT_GNSS_FIX_TIME);
    FUZZ_CHECK(!(f->present & ATT_GNSS_HAS_VALID) || f->valid <= 1);
    FUZZ_CHECK(f->sources != 0 && f->sources < 32);
}

static void misuse(const att_gnss_parser *p)
{
    att_gnss_parser q = *p;
    att_gnss_fix f;
    size_t u, k;
    FUZZ_CHECK(att_gnss_init(NULL) == ATT_GNSS_E_NULL && att_gnss_feed(NULL, 0, &f) == ATT_GNSS_E_NULL);
    FUZZ_CHECK(att_gnss_feed(&q, 0, NULL) == ATT_GNSS_E_NULL && att_gnss_flush(NULL, &f) == ATT_GNSS_E_NULL);
    FUZZ_CHECK(att_gnss_feed_buf(&q, NULL, 1, &f, 1, &u, &k) == ATT_GNSS_E_NULL);
    q.state = 0xFF;
    FUZZ_CHECK(att_gnss_feed(&q, '$', &f) == ATT_GNSS_E_STATE && att_gnss_flush(&q, &f) == ATT_GNSS_E_STATE);
}

/* The never-stuck oracle: resync distance, then a valid sentence. */
static void never_stuck(att_gnss_parser *p)
{
    static const char HEX[] = "0123456789ABCDEF";
    att_gnss_fix f;
    size_t i;
    uint8_t x = 0;
    for (i = 0; i < (size_t)ATT_GNSS_UBX_SKIP_MAX + 8; i++) {
        FUZZ_CHECK(att_gnss_feed(p, 0, &f) >= 0);
    }
    (void)att_gnss_flush(p, &f);
    for (i = 0; i < sizeof GOOD - 1; i++) {
        x = (uint8_t)(x ^ (i > 0 && GOOD[i] != '*' ? (uint8_t)GOOD[i] : 0));
        FUZZ_CHECK(att_gnss_feed(p, (uint8_t)GOOD[i], &f) == ATT_GNSS_NONE);
    }
    FUZZ_CHECK(att_gnss_feed(p, (uint8_t)HEX[x >> 4], &f) == ATT_GNSS_NONE);
    FUZZ_CHECK(att_gnss_feed(p, (uint8_t)HEX[x & 15], &f) == ATT_GNSS_MESSAGE);
    FUZZ_CHECK(att_gnss_flush(p, &f) == ATT_GNSS_FIX);
    FUZZ_CHECK(f.sources == ATT_GNSS_SRC_GGA && f.sats == 7 && f.lat < 0 && f.lon < 0 && f.height_msl < 0);
}

/* Two fixes field by field (no memcmp: the struct has padding). */
static int same_fix(const att_gnss_fix *a, const att_gnss_fix *b)
{
    return a->present == b->present && a->sources == b->sources && a->tod == b->tod && a->lat == b->lat
           && a->lon == b->lon && a->speed == b->speed && a->vel_n == b->vel_n && a->hdop == b->hdop
           && a->fix_type == b->fix_type && a->valid == b->valid && a->sats == b->sats && a->year == b->year;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static uint8_t s[MAX_IN + TEMPLATE_MAX];
    static att_gnss_parser p, q;
    att_gnss_fix f, buf[4];
    size_t i = 0, n, used, k, j, fixes = 0, total = 0, cap;
    uint8_t mode;
    if (size < 1 || size - 1 > MAX_IN) {
        return 0;
    }
    mode = data[0];
    n = size - 1;
    memcpy(s, data + 1, n);
    if (mode & 0x10) {
        n = from_template(s, data + 1, n);
    }
    if (mode & 1) {
        fix_checksums(s, n);
    }
    FUZZ_CHECK(att_gnss_init(&p) == ATT_OK && att_gnss_init(&q) == ATT_OK);
    cap = (size_t)((mode >> 2) % 4 + 1);
    while (i < n) {
        FUZZ_CHECK(att_gnss_feed_buf(&q, s + i, (mode & 2) ? n - i : 0, buf, cap, &used, &k) == ATT_OK);
        if (!(mode & 2)) {
            used = n - i;
            k = 0;
        }
        for (j = 0; j < used; j++) {
            att_gnss_result r = att_gnss_feed(&p, s[i + j], &f);
            FUZZ_CHECK(r >= 0 && r <= ATT_GNSS_REJECTED);
            if (r == ATT_GNSS_FIX) {
                check_fix(&f);
                FUZZ_CHECK(!(mode & 2) || (fixes < k && same_fix(&f, &buf[fixes])));
                fixes++;
                total++;
            }
        }
        FUZZ_CHECK(!(mode & 2) || fixes == k);
        fixes = 0;
        i += used;
    }
    FUZZ_CHECK(p.stats.bytes == n
               && (!(mode & 2) || memcmp(&p.stats, &q.stats, sizeof p.stats) == 0)); /* all uint32 */
    if (att_gnss_flush(&p, &f) == ATT_GNSS_FIX) {
        check_fix(&f);
        total++;
    }
    FUZZ_CHECK(p.stats.fixes == total && p.stats.ubx_accepted <= total);
    /* the template unedited: two NAV-PVT, two NMEA epochs */
    FUZZ_CHECK(!((mode & 0x10) && size < 3)
               || (total == 4 && p.stats.ubx_accepted == 2 && p.stats.nmea_accepted == 8));
    if (mode == 0xA5) {
        misuse(&p);
    }
    never_stuck(&p);
    return 0;
}
