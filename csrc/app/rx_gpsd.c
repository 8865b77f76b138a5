/*
 * attitude-rx: the gpsd input (--gnss gpsd[:HOST[:PORT]]), a libgps client.
 * Built only when the build found libgps (ATT_RX_GPSD defined: invoke
 * cross-build, make, CMake probe for it); otherwise --gnss gpsd is refused
 * with one line and RX_EXIT_UNAVAILABLE. libgps is a dependency of this app
 * only, never of libattitude.
 *
 * gpsd's reports become att_gnss_fix, the parser's fix, so the rest of
 * attitude-rx treats both inputs alike: a TPV with a mode is a fix
 * (mode 1 no fix, 2 2-D, 3 3-D); its velocity is NED when gpsd gives it
 * (vel_d only then), else speed and track; DOP and satellites used are
 * the newest SKY's. The socket is read without blocking, in the input
 * thread's poll() (rx_gnss.c).
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <string.h>

#include "rx.h"

#ifdef ATT_RX_GPSD

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <gps.h>

const int rx_gpsd_built = 1;

#define RX_D2R (3.14159265358979323846 / 180.0)

static struct gps_data_t g_gps; /* one gpsd connection per process */
static struct {
    struct timespec time; /* the time of the last fix queued */
    int had_vel;          /* it had a horizontal velocity */
} g_last;

int rx_gpsd_open(rx_gnss *g, char *msg, size_t len)
{
    int fl;
    memset(&g_gps, 0, sizeof g_gps);
    memset(&g_last, 0, sizeof g_last);
    if (gps_open(g->spec.host, g->spec.service, &g_gps) != 0) {
        snprintf(msg, len, "gnss: gpsd at %s:%s is unreachable: %s", g->spec.host, g->spec.service,
                 gps_errstr(errno));
        return RX_EXIT_UNAVAILABLE;
    }
    if (gps_stream(&g_gps, WATCH_ENABLE | WATCH_JSON, NULL) != 0) {
        snprintf(msg, len, "gnss: gpsd at %s:%s refused the watch: %s", g->spec.host, g->spec.service,
                 gps_errstr(errno));
        gps_close(&g_gps);
        return RX_EXIT_UNAVAILABLE;
    }
    fl = fcntl(g_gps.gps_fd, F_GETFL);
    if (fl < 0 || fcntl(g_gps.gps_fd, F_SETFL, fl | O_NONBLOCK) != 0) { /* reads wait in poll() */
        snprintf(msg, len, "gnss: gpsd socket: %s", strerror(errno));
        gps_close(&g_gps);
        return RX_EXIT_UNAVAILABLE;
    }
    g->gpsd = &g_gps;
    g->fd = g_gps.gps_fd;
    return 0;
}

/* A finite double as att_real in *out, with its presence bit. */
static void put(att_gnss_fix *f, uint32_t bit, att_real *out, double v)
{
    if (!isfinite(v))
        return;
    *out = (att_real)v;
    f->present |= bit;
}

static void velocity(const struct gps_data_t *d, att_gnss_fix *f)
{
    const struct gps_fix_t *x = &d->fix;
    if ((d->set & VNED_SET) && isfinite(x->NED.velN) && isfinite(x->NED.velE)) {
        put(f, ATT_GNSS_HAS_VEL_NE, &f->vel_n, x->NED.velN);
        put(f, ATT_GNSS_HAS_VEL_NE, &f->vel_e, x->NED.velE);
        put(f, ATT_GNSS_HAS_VEL_D, &f->vel_d, x->NED.velD);
    } else if (isfinite(x->speed) && isfinite(x->track)) {
        put(f, ATT_GNSS_HAS_VEL_NE, &f->vel_n, x->speed * cos(x->track * RX_D2R));
        put(f, ATT_GNSS_HAS_VEL_NE, &f->vel_e, x->speed * sin(x->track * RX_D2R));
    }
    put(f, ATT_GNSS_HAS_SPEED, &f->speed, x->speed);
    if (isfinite(x->track))
        put(f, ATT_GNSS_HAS_TRACK, &f->track, x->track * RX_D2R);
}

/* The TPV just read as a fix. */
static void to_fix(const struct gps_data_t *d, att_gnss_fix *f)
{
    const struct gps_fix_t *x = &d->fix;
    memset(f, 0, sizeof *f);
    f->fix_type = x->mode >= MODE_3D   ? ATT_GNSS_FIX_3D
                  : x->mode == MODE_2D ? ATT_GNSS_FIX_2D
                                       : ATT_GNSS_FIX_NONE;
    f->valid = x->mode >= MODE_2D;
    f->present = ATT_GNSS_HAS_FIX_TYPE | ATT_GNSS_HAS_VALID;
    if (x->time.tv_sec > 0) {
        put(f, ATT_GNSS_HAS_TOD, &f->tod, (double)(x->time.tv_sec % 86400) + (double)x->time.tv_nsec * 1e-9);
    }
    if (x->mode >= MODE_2D) {
        velocity(d, f);
        put(f, ATT_GNSS_HAS_LATLON, &f->lat, x->latitude * RX_D2R);
        put(f, ATT_GNSS_HAS_LATLON, &f->lon, x->longitude * RX_D2R);
    }
    put(f, ATT_GNSS_HAS_PDOP, &f->pdop, d->dop.pdop);
    put(f, ATT_GNSS_HAS_HDOP, &f->hdop, d->dop.hdop);
    if (d->satellites_used > 0 && d->satellites_used <= ATT_GNSS_MAX_SATS) {
        f->sats = (uint8_t)d->satellites_used;
        f->present |= ATT_GNSS_HAS_SATS;
    }
}

/* gpsd may report one epoch in several TPVs (after each NMEA sentence until it has learnt
 * the receiver's cycle): a fix is queued once per time of validity, the first report that
 * has its horizontal velocity when an earlier one of that time had none. */
static int new_fix(const struct gps_data_t *d, const att_gnss_fix *f)
{
    const int vel = (f->present & ATT_GNSS_HAS_VEL_NE) != 0;
    const int same = d->fix.time.tv_sec == g_last.time.tv_sec && d->fix.time.tv_nsec == g_last.time.tv_nsec;
    if (d->fix.time.tv_sec == 0)
        return 1; /* no time to tell epochs apart */
    if (same && (g_last.had_vel || !vel))
        return 0;
    g_last.time = d->fix.time;
    g_last.had_vel = vel;
    return 1;
}

int rx_gpsd_read(rx_gnss *g)
{
    struct gps_data_t *d = g->gpsd;
    for (;;) {
        int r;
        d->set = 0;
        r = gps_read(d, NULL, 0);
        if (r < 0) {
            rx_log(g->stop, "gnss: gpsd at %s:%s closed the connection; reconnecting every %.3g s",
                   g->spec.host, g->spec.service, g->reopen_delay);
            return -1;
        }
        if (r == 0)
            return 0; /* no complete report waiting */
        pthread_mutex_lock(&g->lock);
        g->n.reports++;
        pthread_mutex_unlock(&g->lock);
        if ((d->set & MODE_SET) && d->fix.mode >= MODE_NO_FIX) {
            att_gnss_fix f;
            to_fix(d, &f);
            if (new_fix(d, &f))
                rx_gnss_push(g, &f, rx_mono_now());
        }
    }
}

void rx_gpsd_close(rx_gnss *g)
{
    if (g->gpsd != NULL) {
        (void)gps_stream(g->gpsd, WATCH_DISABLE, NULL);
        gps_close(g->gpsd);
    }
    g->gpsd = NULL;
    g->fd = -1;
}

#else /* built without libgps */

const int rx_gpsd_built = 0;

int rx_gpsd_open(rx_gnss *g, char *msg, size_t len)
{
    (void)g;
    snprintf(msg, len,
             "gnss: this attitude-rx was built without gpsd support (no libgps at build time: attitude-rx "
             "--version says); use --gnss /dev/ttyXXX[:BAUD]");
    return RX_EXIT_UNAVAILABLE;
}

int rx_gpsd_read(rx_gnss *g)
{
    (void)g;
    return -1;
}

void rx_gpsd_close(rx_gnss *g)
{
    g->fd = -1;
}

#endif
