/*
 * attitude-rx: the GNSS input (--gnss; docs/gnss.md "attitude-rx's GNSS input").
 * A thread reads the receiver — a serial port through the library's own
 * NMEA 0183 / UBX NAV-PVT parser (attitude/gnss.h), or gpsd (rx_gpsd.c) —
 * and queues each fix with the CLOCK_MONOTONIC time it was read; the
 * attitude thread puts it on the board stream's clock and gives it to the
 * filter between the sample updates (attitude_rx.c). Every wait is a poll()
 * that also watches the stop pipe.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "rx.h"

double rx_mono_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

/* The whole of s as a decimal integer in lo..hi: 0, or -1. */
static int parse_range(const char *s, long lo, long hi, long *out)
{
    char *end;
    long v = strtol(s, &end, 10);
    if (*s == '\0' || *end != '\0' || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

/* "HOST[:PORT]" after "gpsd:" (an IPv6 address in brackets: "[::1]:2947"). */
static int parse_gpsd(const char *s, rx_gnss_spec *o, char *msg, size_t len)
{
    const char *arg = s; /* as given, for the message */
    const char *colon = s[0] == '[' ? strchr(s, ']') : s;
    size_t hn;
    colon = colon ? strchr(colon, ':') : NULL;
    hn = colon ? (size_t)(colon - s) : strlen(s);
    if (s[0] == '[' && hn >= 2 && s[hn - 1] == ']') {
        s++;
        hn -= 2;
    }
    if (hn == 0 || hn >= sizeof o->host
        || (colon && (colon[1] == '\0' || strlen(colon + 1) >= sizeof o->service))) {
        snprintf(msg, len, "gnss: 'gpsd:%s' must be gpsd, gpsd:HOST or gpsd:HOST:PORT", arg);
        return RX_EXIT_CONFIG;
    }
    memcpy(o->host, s, hn);
    o->host[hn] = '\0';
    if (colon) {
        long p;
        if (parse_range(colon + 1, 1, 65535, &p) != 0) {
            snprintf(msg, len, "gnss: gpsd port '%s' must be 1..65535", colon + 1);
            return RX_EXIT_CONFIG;
        }
        snprintf(o->service, sizeof o->service, "%ld", p);
    }
    return 0;
}

/* "PATH[:BAUD]": a device path (absolute), then an optional rate. */
static int parse_serial(const char *s, rx_gnss_spec *o, char *msg, size_t len)
{
    const char *colon = strrchr(s, ':');
    size_t pn = colon ? (size_t)(colon - s) : strlen(s);
    if (s[0] != '/' || pn >= sizeof o->path) {
        snprintf(msg, len, "gnss: '%s' must be gpsd[:HOST[:PORT]] or a serial device /dev/...[:BAUD]", s);
        return RX_EXIT_CONFIG;
    }
    memcpy(o->path, s, pn);
    o->path[pn] = '\0';
    if (colon) {
        long b;
        if (parse_range(colon + 1, 1, 10000000L, &b) != 0 || !rx_serial_baud_ok(b)) {
            snprintf(msg, len, "gnss: baud '%s' is not a supported rate (" RX_BAUDS_TEXT ")", colon + 1);
            return RX_EXIT_CONFIG;
        }
        o->baud = b;
    }
    return 0;
}

int rx_gnss_parse(const char *arg, rx_gnss_spec *out, char *msg, size_t len)
{
    rx_gnss_spec o;
    int rc;
    memset(&o, 0, sizeof o);
    o.baud = RX_GNSS_BAUD_DEFAULT;
    strcpy(o.host, RX_GPSD_HOST_DEFAULT);
    strcpy(o.service, RX_GPSD_PORT_DEFAULT);
    if (strcmp(arg, "off") == 0) {
        o.kind = RX_GNSS_OFF;
    } else if (strcmp(arg, "gpsd") == 0) {
        o.kind = RX_GNSS_GPSD;
    } else if (strncmp(arg, "gpsd:", 5) == 0) {
        o.kind = RX_GNSS_GPSD;
        if ((rc = parse_gpsd(arg + 5, &o, msg, len)) != 0)
            return rc;
    } else {
        o.kind = RX_GNSS_SERIAL;
        if ((rc = parse_serial(arg, &o, msg, len)) != 0)
            return rc;
    }
    *out = o;
    return 0;
}

/* ---- the queue between the input thread and the attitude thread ---- */

void rx_gnss_push(rx_gnss *g, const att_gnss_fix *fix, double wall)
{
    pthread_mutex_lock(&g->lock);
    if (g->count == RX_GNSS_QUEUE) { /* nobody takes them (no board stream yet): keep the newest */
        g->head = (g->head + 1u) % RX_GNSS_QUEUE;
        g->count--;
        g->n.dropped++;
    }
    g->q[(g->head + g->count) % RX_GNSS_QUEUE].fix = *fix;
    g->q[(g->head + g->count) % RX_GNSS_QUEUE].wall = wall;
    g->count++;
    g->n.fixes++;
    pthread_mutex_unlock(&g->lock);
}

int rx_gnss_peek(rx_gnss *g, rx_gnss_item *out)
{
    int got;
    pthread_mutex_lock(&g->lock);
    got = g->count > 0;
    if (got)
        *out = g->q[g->head];
    pthread_mutex_unlock(&g->lock);
    return got;
}

void rx_gnss_pop(rx_gnss *g)
{
    pthread_mutex_lock(&g->lock);
    if (g->count > 0) {
        g->head = (g->head + 1u) % RX_GNSS_QUEUE;
        g->count--;
    }
    pthread_mutex_unlock(&g->lock);
}

rx_gnss_counts rx_gnss_counters(rx_gnss *g)
{
    rx_gnss_counts n;
    pthread_mutex_lock(&g->lock);
    n = g->n;
    pthread_mutex_unlock(&g->lock);
    return n;
}

/* ---- serial: the library's parser ---- */

/* Feed what was read at `wall` to the parser, queueing every fix it completes. */
static void feed(rx_gnss *g, const uint8_t *buf, size_t n, double wall)
{
    att_gnss_fix fixes[8];
    size_t used = 0, nfix = 0, off = 0;
    while (off < n) {
        size_t i;
        if (att_gnss_feed_buf(&g->parser, buf + off, n - off, fixes, sizeof fixes / sizeof fixes[0], &used,
                              &nfix)
            != ATT_OK)
            return; /* not reached: the parser is ours and intact */
        for (i = 0; i < nfix; i++)
            rx_gnss_push(g, &fixes[i], wall);
        off += used;
    }
    pthread_mutex_lock(&g->lock);
    g->n.parser = g->parser.stats;
    pthread_mutex_unlock(&g->lock);
}

/* The NMEA epoch being merged, reported now (the line went quiet, or the end): stamped with
 * the time its last byte was read. */
static void flush(rx_gnss *g, double last_wall)
{
    att_gnss_fix fix;
    if (att_gnss_flush(&g->parser, &fix) == ATT_GNSS_FIX)
        rx_gnss_push(g, &fix, last_wall);
}

/* Read what the port holds now: 1 = data, 0 = nothing, -1 = the port went away. */
static int read_port(rx_gnss *g, double *last_wall)
{
    uint8_t buf[512];
    ssize_t got = read(g->fd, buf, sizeof buf);
    if (got < 0 && (errno == EINTR || errno == EAGAIN))
        return 0;
    if (got <= 0) {
        rx_log(g->stop, "gnss: port %s %s; reopening every %.3g s", g->spec.path,
               got == 0 ? "closed" : strerror(errno), g->reopen_delay);
        return -1;
    }
    *last_wall = rx_mono_now();
    feed(g, buf, (size_t)got, *last_wall);
    return 1;
}

static void lost(rx_gnss *g)
{
    if (g->spec.kind == RX_GNSS_GPSD)
        rx_gpsd_close(g);
    else
        close(g->fd);
    g->fd = -1;
    pthread_mutex_lock(&g->lock);
    g->n.lost++;
    pthread_mutex_unlock(&g->lock);
}

static int reopen(rx_gnss *g)
{
    char msg[RX_MSG_MAX];
    if (g->spec.kind == RX_GNSS_GPSD)
        return rx_gpsd_open(g, msg, sizeof msg) == 0 ? 0 : -1;
    g->fd = rx_serial_open(g->spec.path, g->spec.baud, msg, sizeof msg);
    return g->fd >= 0 ? 0 : -1;
}

/* One readable event of the input: 0, or -1 when it went away. */
static int take(rx_gnss *g, double *last_wall)
{
    if (g->spec.kind == RX_GNSS_GPSD)
        return rx_gpsd_read(g);
    return read_port(g, last_wall) < 0 ? -1 : 0;
}

/* At the stop: what the input already holds is read (a receiver's last bytes are
 * not lost to the stop's timing), then the epoch being merged is reported. */
static void drain(rx_gnss *g, double last_wall)
{
    struct pollfd p;
    if (g->fd < 0)
        return;
    p.fd = g->fd;
    p.events = POLLIN;
    while (poll(&p, 1, 0) > 0 && (p.revents & POLLIN) && take(g, &last_wall) == 0)
        if (g->spec.kind == RX_GNSS_SERIAL && p.revents & POLLHUP)
            break;
    if (g->spec.kind == RX_GNSS_SERIAL)
        flush(g, last_wall);
}

static void *gnss_thread(void *arg)
{
    rx_gnss *g = arg;
    double last_wall = 0.0;
    int quiet = -1; /* serial: poll timeout (ms) while an NMEA epoch may be open */
    for (;;) {
        struct pollfd p[2];
        int n;
        if (g->fd < 0) {
            if (rx_stop_wait(g->stop, g->reopen_delay))
                break;
            if (reopen(g) == 0)
                rx_log(g->stop, "gnss: %s reopened", g->spec.kind == RX_GNSS_GPSD ? "gpsd" : g->spec.path);
            continue;
        }
        p[0].fd = g->stop->wake_rd;
        p[1].fd = g->fd;
        p[0].events = p[1].events = POLLIN;
        p[0].revents = p[1].revents = 0;
        n = poll(p, 2, quiet);
        if (n < 0 && errno != EINTR)
            break;
        if (n > 0 && (p[0].revents & POLLIN) && rx_stop_check(g->stop))
            break;
        if (n == 0) { /* the line went quiet: the epoch is complete */
            flush(g, last_wall);
            quiet = -1;
        } else if (n > 0 && (p[1].revents & (POLLIN | POLLHUP | POLLERR))) {
            if (take(g, &last_wall) < 0)
                lost(g);
            else if (g->spec.kind == RX_GNSS_SERIAL)
                quiet = RX_GNSS_QUIET_MS;
        }
    }
    drain(g, last_wall);
    return NULL;
}

int rx_gnss_open(rx_gnss *g, const rx_gnss_spec *spec, rx_stop *stop, double reopen_delay, char *msg,
                 size_t len)
{
    memset(g, 0, sizeof *g);
    g->spec = *spec;
    g->stop = stop;
    g->reopen_delay = reopen_delay;
    g->fd = -1;
    if (pthread_mutex_init(&g->lock, NULL) != 0) {
        snprintf(msg, len, "gnss: cannot set up its lock: %s", strerror(errno));
        return RX_EXIT_INTERNAL;
    }
    if (spec->kind == RX_GNSS_GPSD)
        return rx_gpsd_open(g, msg, len);
    if (spec->kind == RX_GNSS_SERIAL) {
        att_gnss_init(&g->parser);
        g->fd = rx_serial_open(spec->path, spec->baud, msg, len);
        if (g->fd < 0) {
            int e = errno;
            char inner[RX_MSG_MAX];
            snprintf(inner, sizeof inner, "%s", msg);
            snprintf(msg, len, "gnss: %s", inner);
            return rx_open_error_code(e);
        }
    }
    return 0;
}

int rx_gnss_start(rx_gnss *g)
{
    if (g->spec.kind == RX_GNSS_OFF)
        return 0;
    if (pthread_create(&g->thread, NULL, gnss_thread, g) != 0)
        return -1;
    g->started = 1;
    return 0;
}

void rx_gnss_end(rx_gnss *g)
{
    if (g->started)
        pthread_join(g->thread, NULL);
    g->started = 0;
    if (g->fd >= 0) {
        if (g->spec.kind == RX_GNSS_GPSD)
            rx_gpsd_close(g);
        else
            close(g->fd);
    }
    g->fd = -1;
}

/* ---- the attitude thread's side: clock and output ---- */

void rx_gnss_clock_sample(rx_gnss_clock *c, double wall, double t)
{
    double d = wall - t;
    if (!c->known || d < c->offset + RX_GNSS_CLOCK_LEAK * (t - c->t))
        c->offset = d;
    else
        c->offset += RX_GNSS_CLOCK_LEAK * (t - c->t);
    c->t = t;
    c->known = 1;
}

double rx_gnss_clock_time(const rx_gnss_clock *c, double wall, double latency)
{
    return wall - c->offset - latency;
}

const char *rx_gnss_source(rx_gnss_kind k)
{
    return k == RX_GNSS_GPSD ? "gpsd" : "serial";
}

/* "%.*g" of v, or null when the fix lacks it. */
static int num(char *p, size_t len, const att_gnss_fix *f, uint32_t bit, double v)
{
    const int digits = att_real_size() == 4 ? 9 : 17;
    return (f->present & bit) ? snprintf(p, len, "%.*g", digits, v) : snprintf(p, len, "null");
}

#define RX_GNSS_R2D (180.0 / 3.14159265358979323846)

int rx_gnss_json(char *p, size_t len, const att_gnss_fix *f, double age_s, const char *source)
{
    static const char *const fix_names[] = { "none", "dr", "2d", "3d", "gnss_dr", "time" };
    size_t n = 0;
#define RX_PUT(call)                         \
    do {                                     \
        int w_ = (call);                     \
        if (w_ < 0 || (size_t)w_ >= len - n) \
            return -1;                       \
        n += (size_t)w_;                     \
    } while (0)
    RX_PUT(snprintf(p + n, len - n, ",\"gnss\":{\"fix\":\"%s\",\"valid\":%s,\"speed\":",
                    (f->present & ATT_GNSS_HAS_FIX_TYPE) && f->fix_type <= ATT_GNSS_FIX_TIME
                        ? fix_names[f->fix_type]
                        : "none",
                    (f->present & ATT_GNSS_HAS_VALID) && f->valid ? "true" : "false"));
    RX_PUT(num(p + n, len - n, f, ATT_GNSS_HAS_SPEED, (double)f->speed));
    RX_PUT(snprintf(p + n, len - n, ",\"track_deg\":"));
    RX_PUT(num(p + n, len - n, f, ATT_GNSS_HAS_TRACK, (double)f->track * RX_GNSS_R2D));
    RX_PUT(snprintf(p + n, len - n, ",\"vel_enu\":"));
    if (f->present & ATT_GNSS_HAS_VEL_NE) {
        RX_PUT(snprintf(p + n, len - n, "["));
        RX_PUT(num(p + n, len - n, f, ATT_GNSS_HAS_VEL_NE, (double)f->vel_e));
        RX_PUT(snprintf(p + n, len - n, ","));
        RX_PUT(num(p + n, len - n, f, ATT_GNSS_HAS_VEL_NE, (double)f->vel_n));
        RX_PUT(snprintf(p + n, len - n, ","));
        RX_PUT(num(p + n, len - n, f, ATT_GNSS_HAS_VEL_D, -(double)f->vel_d));
        RX_PUT(snprintf(p + n, len - n, "]"));
    } else {
        RX_PUT(snprintf(p + n, len - n, "null"));
    }
    RX_PUT(snprintf(p + n, len - n, ",\"sats\":"));
    RX_PUT(num(p + n, len - n, f, ATT_GNSS_HAS_SATS, (double)f->sats));
    RX_PUT(snprintf(p + n, len - n, ",\"pdop\":"));
    RX_PUT(num(p + n, len - n, f, ATT_GNSS_HAS_PDOP, (double)f->pdop));
    RX_PUT(snprintf(p + n, len - n, ",\"age_s\":%.6g,\"source\":\"%s\"}", age_s, source));
#undef RX_PUT
    return (int)n;
}
