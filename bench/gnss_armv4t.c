/*
 * Instruction-count harness for bench/gnss_parse.py: the GNSS parser
 * (attitude/gnss.h) fed byte by byte with att_gnss_feed, as attitude-rx's
 * serial input would.
 *
 *   gnss_armv4t MODE N
 *     MODE = rmc   N RMC sentences, times alternating (each closes an epoch: one fix per sentence)
 *            epoch N epochs of RMC, VTG, GGA, GSA (the NMEA 0183 example), times alternating
 *            pvt   N UBX NAV-PVT frames
 *     N    = messages / epochs
 *
 * The streams are fixed tables (built once at start-up: toolchain/qemu_count.py's
 * difference of two N cancels that); the last fix's fields are summed into a
 * volatile so nothing is optimised away.
 */
#include <stdlib.h>
#include <string.h>

#include "attitude/attitude.h"

static const char *const RMC[2] = {
    "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A\r\n",
    "$GPRMC,123520,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*60\r\n",
};
static const char *const REST[2] = {
    "$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*48\r\n"
    "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n"
    "$GPGSA,A,3,04,05,,09,12,,,24,,,,,2.5,1.3,2.1*39\r\n",
    "$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*48\r\n"
    "$GPGGA,123520,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*4D\r\n"
    "$GPGSA,A,3,04,05,,09,12,,,24,,,,,2.5,1.3,2.1*39\r\n",
};

static uint8_t pvt[100];
static volatile att_real sink;

static void put(unsigned off, unsigned long v, int n)
{
    int i;
    for (i = 0; i < n; i++) {
        pvt[6 + off + (unsigned)i] = (uint8_t)(v >> (8 * i));
    }
}

/* A NAV-PVT frame: a 3D fix moving north-east at 13 m/s. */
static void make_pvt(void)
{
    unsigned k;
    uint8_t a = 0, b = 0;
    pvt[0] = 0xB5;
    pvt[1] = 0x62;
    pvt[2] = 0x01;
    pvt[3] = 0x07;
    pvt[4] = 92;
    put(0, 345600250ul, 4);
    put(4, 2026, 2);
    put(6, 0x1C0B, 2);
    put(8, 0x070514, 3);
    pvt[6 + 11] = 0x07;
    put(20, 0x0E0103, 4);
    put(24, (unsigned long)-1227000000L, 4);
    put(28, 374000000ul, 4);
    put(36, 20000ul, 4);
    put(48, 9192ul, 4);
    put(52, 9192ul, 4);
    put(60, 13000ul, 4);
    put(64, 4500000ul, 4);
    put(76, 187ul, 2);
    for (k = 2; k < 98; k++) {
        a = (uint8_t)(a + pvt[k]);
        b = (uint8_t)(b + a);
    }
    pvt[98] = a;
    pvt[99] = b;
}

static void feed(att_gnss_parser *p, const uint8_t *s, size_t n, att_gnss_fix *f)
{
    size_t i;
    for (i = 0; i < n; i++) {
        if (att_gnss_feed(p, s[i], f) == ATT_GNSS_FIX) {
            sink = f->vel_n + f->lat;
        }
    }
}

int main(int argc, char **argv)
{
    att_gnss_parser p;
    att_gnss_fix f;
    long i, n;
    if (argc != 3) {
        return 2;
    }
    n = atol(argv[2]);
    make_pvt();
    att_gnss_init(&p);
    for (i = 0; i < n; i++) {
        const char *r = RMC[i & 1];
        if (strcmp(argv[1], "pvt") == 0) {
            feed(&p, pvt, sizeof pvt, &f);
            continue;
        }
        feed(&p, (const uint8_t *)r, strlen(r), &f);
        if (strcmp(argv[1], "epoch") == 0) {
            feed(&p, (const uint8_t *)REST[i & 1], strlen(REST[i & 1]), &f);
        }
    }
    return p.stats.bad_checksum == 0 && p.stats.bad_field == 0 && p.stats.fixes + 1 >= (uint32_t)n ? 0 : 1;
}
