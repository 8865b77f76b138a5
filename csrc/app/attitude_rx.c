/*
 * attitude-rx — the Linux computer's main program (paper sec. 3.3–3.4,
 * Fig. 6): a receiver thread runs the link receiver B on the serial port,
 * decodes every record of every accepted block with the block format of
 * libattitude (attitude/block.h: samples and the firmware's reports) and
 * numbers it (loss accounting by sequence number), and puts it into a
 * bounded queue; an attitude thread takes the records in stream order,
 * converts ADC codes to angle increments (or rates for rk4), runs the
 * integrator and prints one line per attitude update, and logs every
 * report (stderr, and a JSON Lines record with --format jsonl).
 *
 * Missing samples are never skipped silently: a loss report (GAVE_UP,
 * OVERRUN, ADC_ERROR), a sample whose code is outside 0..4095, a gap in
 * the numbering and samples dropped on a full queue are each filled by
 * holding the last good rate over the missing sample periods, so the time
 * base stays the firmware's; they are counted (held, missing). The sample
 * period comes from the BOOT report unless --period is given.
 *
 * SIGINT/SIGTERM (or --count) stop it cleanly: the receiver stops, the
 * attitude thread finishes the records already queued, the link, sample
 * and report statistics go to stderr. A port that disappears (EIO,
 * hang-up) is reported and reopened every --reopen-delay seconds, never
 * spun on.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "rx.h"

typedef struct {
    rx_config cfg;
    rx_queue queue;
    int fd;                       /* serial port (owned by the receiver thread once started) */
    int wake_rd, wake_wr;         /* self-pipe: stop requests (signal handler, --count) */
    att_link_receiver_stats link; /* copied by the receiver thread when it ends */
    /* receiver thread */
    unsigned long samples;       /* sample records received in accepted blocks (good or not) */
    unsigned long queue_missing; /* samples dropped on a full queue */
    unsigned long port_errors, reopens;
    /* attitude thread */
    unsigned long integrated, held, missing, updates, integ_errors, code_errors;
    unsigned long reports[ATT_BLOCK_OVERSAMPLE + 1];
    unsigned long block_errors, seq_errors;
    double period; /* s, the sample period in use */
    double t;      /* s, time integrated so far (sample periods, held ones included) */
    int out_error; /* stdout failed (closed pipe) */
} rx_app;

static const char *const report_names[ATT_BLOCK_OVERSAMPLE + 1] = { "BOOT",    "SELFTEST",  "GAVE_UP",
                                                                    "OVERRUN", "ADC_ERROR", "OVERSAMPLE" };

static int g_wake_wr = -1; /* for the signal handler only */
static volatile sig_atomic_t g_signal = 0;

static void on_signal(int sig)
{
    char c = 's';
    ssize_t r;
    g_signal = sig;
    r = write(g_wake_wr, &c, 1);
    (void)r;
}

static void request_stop(rx_app *app)
{
    char c = 'c';
    ssize_t r = write(app->wake_wr, &c, 1);
    (void)r;
}

static uint16_t now_tick(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint16_t)((unsigned long)ts.tv_sec * 1000UL + (unsigned long)(ts.tv_nsec / 1000000L));
}

static int write_all(int fd, const uint8_t *p, size_t n)
{
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0) {
            if (errno == EINTR || errno == EAGAIN)
                continue;
            return -1;
        }
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

/* Hand out everything the receiver wants to send (0xBB, 0x00, 0xFF). */
static int drain_receiver(att_link_receiver *r, int fd)
{
    for (;;) {
        uint8_t out;
        att_link_result res = att_link_receiver_poll(r, now_tick(), &out);
        if (res == ATT_LINK_SEND) {
            if (write_all(fd, &out, 1) != 0)
                return -1;
        } else if (res == ATT_LINK_TIMEOUT) {
            continue;
        } else {
            return 0;
        }
    }
}

/* Wait up to `seconds` for a stop request; 1 if one came. */
static int wait_stop(rx_app *app, double seconds)
{
    struct pollfd p;
    p.fd = app->wake_rd;
    p.events = POLLIN;
    p.revents = 0;
    return poll(&p, 1, (int)(seconds * 1000.0)) > 0;
}

static void port_lost(rx_app *app, const char *what, int err)
{
    fprintf(stderr, "attitude-rx: port %s %s: %s; reopening every %.3g s\n", app->cfg.port, what,
            err ? strerror(err) : "hang-up", app->cfg.reopen_delay);
    app->port_errors++;
    close(app->fd);
    app->fd = -1;
}

/* Decode and number one record (attitude/block.h) and queue it. Records
 * that find the queue full are counted; the samples they stood for are
 * handed on with the next record that gets through (missing), so the
 * attitude thread fills them like any other loss. */
static void queue_record(rx_app *app, att_block_seq *seq, const uint8_t *raw, uint32_t *missing_first,
                         uint32_t *missing)
{
    rx_item it;
    memset(&it, 0, sizeof it);
    memcpy(it.raw, raw, sizeof it.raw);
    it.status = att_block_seq_decode(seq, raw, &it.blk, &it.span); /* a bad sample still takes its number */
    if (it.status == ATT_BLOCK_E_SEQ) {
        it.seq_status = it.status;
        it.status = ATT_OK;
    }
    if (it.blk.kind == ATT_BLOCK_SAMPLE)
        app->samples++;
    it.missing_first = *missing_first;
    it.missing = *missing;
    if (rx_queue_push(&app->queue, &it) == 0) {
        *missing = 0;
    } else if (it.status == ATT_OK || it.status == ATT_BLOCK_E_CODE) {
        if (*missing == 0)
            *missing_first = it.span.first;
        *missing += it.span.count; /* a dropped sample: 1; a dropped loss report: its samples */
        app->queue_missing += it.span.count;
    }
}

static void *receiver_thread(void *arg)
{
    rx_app *app = arg;
    att_link_receiver r;
    att_link_receiver_config rc;
    uint8_t block[ATT_LINK_BLOCK_MAX];
    uint8_t buf[256];
    att_block_seq seq;
    uint32_t missing_first = 0, missing = 0; /* samples dropped on a full queue, not yet told */

    att_block_seq_init(&seq);
    att_link_receiver_config_init(&rc, (uint8_t)app->cfg.block_size);
    rc.gap_timeout = (uint16_t)app->cfg.gap_ms;
    if (att_link_receiver_init(&r, &rc, block) != ATT_OK) {
        fprintf(stderr, "attitude-rx: link receiver configuration rejected\n");
        request_stop(app);
        return NULL;
    }
    for (;;) {
        struct pollfd p[2];
        int timeout, n;
        uint16_t left;
        if (app->fd < 0) { /* port gone: retry, sleeping in between */
            char msg[RX_MSG_MAX];
            if (wait_stop(app, app->cfg.reopen_delay))
                break;
            app->fd = rx_serial_open(app->cfg.port, app->cfg.baud, msg, sizeof msg);
            if (app->fd < 0)
                continue;
            fprintf(stderr, "attitude-rx: port %s reopened\n", app->cfg.port);
            app->reopens++;
            att_link_receiver_reset(&r);
        }
        left = att_link_receiver_ticks_left(&r, now_tick());
        timeout = (left == ATT_LINK_NO_TIMER || left > 100) ? 100 : (int)left;
        p[0].fd = app->fd;
        p[0].events = POLLIN;
        p[1].fd = app->wake_rd;
        p[1].events = POLLIN;
        p[0].revents = p[1].revents = 0;
        n = poll(p, 2, timeout);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            fprintf(stderr, "attitude-rx: poll: %s\n", strerror(errno));
            break;
        }
        if (p[1].revents & POLLIN)
            break;
        if (p[0].revents & (POLLIN | POLLHUP | POLLERR)) {
            ssize_t got = read(app->fd, buf, sizeof buf);
            ssize_t i;
            if (got < 0 && (errno == EINTR || errno == EAGAIN))
                continue;
            if (got <= 0) {
                port_lost(app, got == 0 ? "closed" : "read failed", got == 0 ? 0 : errno);
                continue;
            }
            for (i = 0; i < got; i++) {
                att_link_result res = att_link_receiver_sink(&r, buf[i], now_tick());
                if (res == ATT_LINK_ACCEPTED) {
                    unsigned k;
                    for (k = 0; k + ATT_BLOCK_SIZE <= app->cfg.block_size; k += ATT_BLOCK_SIZE)
                        queue_record(app, &seq, block + k, &missing_first, &missing);
                }
                /* answer at once (the sender waits for 0xBB / 0x00 / 0xFF) */
                if (drain_receiver(&r, app->fd) != 0) {
                    port_lost(app, "write failed", errno);
                    break;
                }
            }
        } else if (drain_receiver(&r, app->fd) != 0) { /* gap timer */
            port_lost(app, "write failed", errno);
        }
    }
    app->link = r.stats;
    return NULL;
}

static void print_header(const rx_app *app)
{
    if (app->cfg.format == RX_FORMAT_CSV && app->cfg.header)
        printf("t,n,code_x,code_y,code_z,q0,q1,q2,q3,yaw_deg,pitch_deg,roll_deg,heading_deg\n");
}

/* Flush stdout; on failure (closed pipe) stop. */
static void out_done(rx_app *app, int rc)
{
    if (rc < 0 || fflush(stdout) != 0) {
        app->out_error = 1;
        request_stop(app);
    }
}

static void print_update(rx_app *app, uint32_t n, const uint16_t code[3], const att_real q[4])
{
    att_real e[3], h = 0;
    const double r2d = 180.0 / 3.14159265358979323846;
    const int digits = att_real_size() == 4 ? 9 : 17; /* round-trip precision */
    double t = app->t;
    int rc;
    if (att_quat_to_euler(q, e) != ATT_OK || att_quat_heading(q, &h) != ATT_OK)
        e[0] = e[1] = e[2] = h = (att_real)0;
    if (app->cfg.format == RX_FORMAT_CSV)
        rc = printf("%.9g,%lu,%u,%u,%u,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g\n", t, (unsigned long)n,
                    code[0], code[1], code[2], digits, (double)q[0], digits, (double)q[1], digits,
                    (double)q[2], digits, (double)q[3], digits, (double)e[0] * r2d, digits,
                    (double)e[1] * r2d, digits, (double)e[2] * r2d, digits, (double)h * r2d);
    else
        rc = printf(
            "{\"t\":%.9g,\"n\":%lu,\"codes\":[%u,%u,%u],\"q\":[%.*g,%.*g,%.*g,%.*g],"
            "\"yaw_deg\":%.*g,\"pitch_deg\":%.*g,\"roll_deg\":%.*g,\"heading_deg\":%.*g,\"held\":%lu}\n",
            t, (unsigned long)n, code[0], code[1], code[2], digits, (double)q[0], digits, (double)q[1],
            digits, (double)q[2], digits, (double)q[3], digits, (double)e[0] * r2d, digits,
            (double)e[1] * r2d, digits, (double)e[2] * r2d, digits, (double)h * r2d, app->held);
    out_done(app, rc);
}

/* The attitude thread's integration state. */
typedef struct {
    att_integ integ;
    att_sensor gyro;    /* codes -> body rate (--gyro-zero, --gyro-scale, --axes) */
    uint8_t oversample; /* conversions per sample word: 1, or the stream's OVERSAMPLE */
    att_real rate[3];   /* body rate of the last good sample, rad/s */
    uint16_t code[3];   /* its codes */
    int have_rate;      /* a good sample has been integrated */
} rx_att;

static int finished(const rx_app *app)
{
    return app->out_error || (app->cfg.count && app->updates >= app->cfg.count);
}

/* Integrate one sample period (number n) at body rate v; codes for the output line. */
static void integrate(rx_app *app, rx_att *a, uint32_t n, const att_real v[3], const uint16_t code[3])
{
    const rx_config *c = &app->cfg;
    att_real d[3], q[4];
    int i, rc;
    if (c->method == ATT_METHOD_RK4) {
        rc = att_integ_update_rate(&a->integ, v, (att_real)(2.0 * app->period), q);
    } else {
        for (i = 0; i < 3; i++)
            d[i] = (att_real)((double)v[i] * app->period); /* rad per sample interval */
        rc = att_integ_update(&a->integ, d, q);
    }
    if (rc < 0) {
        app->integ_errors++;
        fprintf(stderr, "attitude-rx: sample %lu rejected by the integrator: %s\n", (unsigned long)n,
                att_status_str(rc));
        return;
    }
    app->t += app->period;
    if (rc == ATT_INTEG_UPDATED) {
        app->updates++;
        print_update(app, n, code, q);
        if (c->count && app->updates >= c->count)
            request_stop(app);
    }
}

/* Samples first .. first + n - 1 will never come (why: for the log): hold
 * the last good rate over them, or, before the first good sample, only
 * let the time pass. */
static void hold(rx_app *app, rx_att *a, uint32_t first, uint32_t n, const char *why)
{
    uint32_t k;
    char which[48];
    if (n == 1u)
        snprintf(which, sizeof which, "sample %lu", (unsigned long)first);
    else
        snprintf(which, sizeof which, "samples %lu..%lu", (unsigned long)first,
                 (unsigned long)(first + n - 1u));
    app->missing += n;
    if (!a->have_rate) {
        fprintf(stderr, "attitude-rx: %s missing (%s) before the first sample: no rate to hold\n", which,
                why);
        app->t += (double)n * app->period;
        return;
    }
    fprintf(stderr, "attitude-rx: %s missing (%s): holding the last rate over %lu sample period%s\n", which,
            why, (unsigned long)n, n == 1u ? "" : "s");
    for (k = 0; k < n && !finished(app); k++) {
        app->held++;
        integrate(app, a, first + k, a->rate, a->code);
    }
}

/* A good sample: codes -> body rate (calibration, axes: att_sensor) -> integrator. */
static void sample(rx_app *app, rx_att *a, const rx_item *it)
{
    int i;
    if (att_sensor_convert(&a->gyro, it->blk.code, a->oversample, a->rate) != ATT_OK)
        return; /* not reached: the tracker checked the codes against the stream's limit */
    for (i = 0; i < 3; i++)
        a->code[i] = it->blk.code[i];
    a->have_rate = 1;
    app->integrated++;
    integrate(app, a, it->span.first, a->rate, a->code);
}

/* JSON Lines record for a report or an error (--format jsonl only); body: ,"key":value... */
static void json_record(rx_app *app, const char *body)
{
    if (app->cfg.format == RX_FORMAT_JSONL)
        out_done(app, printf("{\"t\":%.9g,%s}\n", app->t, body));
}

static void boot(rx_app *app, const att_block *b)
{
    char body[RX_MSG_MAX];
    double p = (double)b->period_ticks / (double)ATT_BLOCK_TICK_HZ;
    long baud = (long)b->baud_div * ATT_BLOCK_BAUD_UNIT;
    fprintf(stderr, "attitude-rx: BOOT: block format %u, sample period %u ticks = %g s, %ld baud\n",
            b->version, b->period_ticks, p, baud);
    if (!app->cfg.period_set) {
        app->period = p;
    } else if (fabs(p - app->cfg.period) > 1e-9 * p) {
        fprintf(stderr,
                "attitude-rx: warning: the board samples every %g s (BOOT) but --period %g s was "
                "given: integrating with %g s\n",
                p, app->cfg.period, app->cfg.period);
    }
    if (baud != app->cfg.baud)
        fprintf(stderr, "attitude-rx: warning: the board announces %ld baud, the port runs at %ld\n", baud,
                app->cfg.baud);
    snprintf(body, sizeof body,
             "\"report\":\"BOOT\",\"version\":%u,\"period_ticks\":%u,\"period_s\":%.9g,\"baud\":%ld,"
             "\"period_used_s\":%.9g",
             b->version, b->period_ticks, p, baud, app->period);
    json_record(app, body);
}

static void report(rx_app *app, rx_att *a, const rx_item *it)
{
    const att_block *b = &it->blk;
    char body[RX_MSG_MAX];
    const char *name = report_names[b->kind];
    app->reports[b->kind]++;
    if (b->kind == ATT_BLOCK_BOOT) {
        a->oversample = 1; /* a new stream: plain codes until an OVERSAMPLE report */
        boot(app, b);
        return;
    }
    if (b->kind == ATT_BLOCK_OVERSAMPLE) {
        a->oversample = b->oversample;
        fprintf(stderr, "attitude-rx: OVERSAMPLE: each sample word is the sum of %u conversions\n",
                b->oversample);
        snprintf(body, sizeof body, "\"report\":\"OVERSAMPLE\",\"n\":%u", b->oversample);
        json_record(app, body);
        return;
    }
    if (b->kind == ATT_BLOCK_SELFTEST) {
        fprintf(stderr, "attitude-rx: SELFTEST failed: status %d, code %u, attempt %u\n", b->status,
                b->bad_code, b->attempt);
        snprintf(body, sizeof body, "\"report\":\"SELFTEST\",\"status\":%d,\"bad_code\":%u,\"attempt\":%u",
                 b->status, b->bad_code, b->attempt);
        json_record(app, body);
        return;
    }
    /* a loss report: span = the samples missing here (an unreported gap included) */
    if (it->seq_status == ATT_BLOCK_E_SEQ) {
        app->seq_errors++;
        fprintf(stderr, "attitude-rx: %s for sample %u, but %ld sample%s %s: numbering follows the report\n",
                name, b->first, (long)(it->span.slip < 0 ? -it->span.slip : it->span.slip),
                (it->span.slip == 1 || it->span.slip == -1) ? "" : "s",
                it->span.slip > 0 ? "vanished unreported before it" : "were counted twice");
    }
    fprintf(stderr, "attitude-rx: %s: %u sample%s lost at sample %u", name, b->count,
            b->count == 1u ? "" : "s", b->first);
    if (b->kind == ATT_BLOCK_ADC_ERROR)
        fprintf(stderr, " (scan status %d)", b->status);
    fputc('\n', stderr);
    snprintf(body, sizeof body, "\"report\":\"%s\",\"first\":%lu,\"count\":%lu,\"slip\":%ld", name,
             (unsigned long)it->span.first, (unsigned long)it->span.count, (long)it->span.slip);
    if (b->kind == ATT_BLOCK_ADC_ERROR)
        snprintf(body + strlen(body), sizeof body - strlen(body), ",\"status\":%d", b->status);
    json_record(app, body);
    hold(app, a, it->span.first, it->span.count, name);
}

/* A record that breaks the format: never integrated. */
static void bad_record(rx_app *app, rx_att *a, const rx_item *it)
{
    char body[RX_MSG_MAX], hex[3 * ATT_BLOCK_SIZE];
    int i;
    for (i = 0; i < ATT_BLOCK_SIZE; i++)
        snprintf(hex + 2 * i, 3, "%02x", it->raw[i]);
    if (it->status == ATT_BLOCK_E_CODE) { /* a sample with a code above 4095: it is missing */
        app->code_errors++;
        fprintf(stderr, "attitude-rx: sample %lu rejected: code out of 0..%d (%u, %u, %u)\n",
                (unsigned long)it->span.first, ATT_BLOCK_CODE_MAX, it->blk.code[0], it->blk.code[1],
                it->blk.code[2]);
        snprintf(body, sizeof body, "\"error\":\"code\",\"n\":%lu,\"codes\":[%u,%u,%u]",
                 (unsigned long)it->span.first, it->blk.code[0], it->blk.code[1], it->blk.code[2]);
        json_record(app, body);
        hold(app, a, it->span.first, 1, "code out of range");
        return;
    }
    app->block_errors++;
    if (it->blk.kind == ATT_BLOCK_BOOT && it->blk.version != ATT_BLOCK_VERSION)
        fprintf(stderr, "attitude-rx: BOOT %s ignored: block format %u, this program reads format %d\n", hex,
                it->blk.version, ATT_BLOCK_VERSION);
    else
        fprintf(stderr, "attitude-rx: record %s ignored: %s\n", hex,
                it->status == ATT_BLOCK_E_KIND ? "unknown report kind" : "report field out of range");
    snprintf(body, sizeof body, "\"error\":\"%s\",\"raw\":\"%s\"",
             it->status == ATT_BLOCK_E_KIND ? "kind" : "field", hex);
    json_record(app, body);
}

static void *attitude_thread(void *arg)
{
    rx_app *app = arg;
    const rx_config *c = &app->cfg;
    rx_att a;
    rx_item it;

    memset(&a, 0, sizeof a);
    a.oversample = 1;
    if (rx_gyro_init(c, &a.gyro) != ATT_OK) {
        fprintf(stderr, "attitude-rx: gyro calibration rejected (--gyro-zero, --gyro-scale, --axes)\n");
        request_stop(app);
        return NULL;
    }
    if (att_integ_init(&a.integ, c->method, NULL) != ATT_OK) {
        fprintf(stderr, "attitude-rx: integrator rejected method %s\n", rx_method_name(c->method));
        request_stop(app);
        return NULL;
    }
    print_header(app);
    while (rx_queue_pop(&app->queue, &it) == 0) {
        if (c->consumer_delay > 0) {
            struct timespec d;
            d.tv_sec = (time_t)c->consumer_delay;
            d.tv_nsec = (long)((c->consumer_delay - (double)d.tv_sec) * 1e9);
            nanosleep(&d, NULL);
        }
        if (finished(app))
            continue; /* finished: just drain */
        if (it.missing != 0)
            hold(app, &a, it.missing_first, it.missing, "queue overflow");
        if (finished(app))
            continue;
        if (it.status != ATT_OK)
            bad_record(app, &a, &it);
        else if (it.blk.kind == ATT_BLOCK_SAMPLE)
            sample(app, &a, &it);
        else
            report(app, &a, &it);
    }
    return NULL;
}

static int open_error_code(int err)
{
    if (err == ENOENT || err == ENODEV || err == ENXIO || err == ENOTDIR)
        return RX_EXIT_NOPORT;
    if (err == EACCES || err == EPERM)
        return RX_EXIT_NOPERM;
    return RX_EXIT_IOERR;
}

int main(int argc, char **argv)
{
    static rx_app app; /* large (queue): not on the stack */
    char msg[RX_MSG_MAX];
    int rc, pipefd[2];
    rx_action action;
    pthread_t rx_thr, att_thr;
    struct sigaction sa;

    rx_config_defaults(&app.cfg);
    rc = rx_config_parse(&app.cfg, argc, argv, &action, msg, sizeof msg);
    if (rc == 0 && action == RX_HELP) {
        rx_usage(argv[0], stdout);
        return RX_EXIT_OK;
    }
    if (rc == 0 && action == RX_VERSION_INFO) {
        printf("attitude-rx %s (libattitude, att_real = %s)\n", RX_VERSION,
               att_real_size() == 4 ? "float" : "double");
        return RX_EXIT_OK;
    }
    if (rc != 0) {
        fprintf(stderr, "attitude-rx: %s\n", msg);
        return rc;
    }
    app.fd = rx_serial_open(app.cfg.port, app.cfg.baud, msg, sizeof msg);
    if (app.fd < 0) {
        int e = errno;
        fprintf(stderr, "attitude-rx: %s\n", msg);
        return open_error_code(e);
    }
    if (pipe(pipefd) != 0 || rx_queue_init(&app.queue, app.cfg.queue_size) != 0) {
        fprintf(stderr, "attitude-rx: cannot set up threads: %s\n", strerror(errno));
        return RX_EXIT_INTERNAL;
    }
    app.wake_rd = pipefd[0];
    app.wake_wr = g_wake_wr = pipefd[1];
    fcntl(app.wake_wr, F_SETFL, fcntl(app.wake_wr, F_GETFL) | O_NONBLOCK);

    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &sa, NULL); /* a closed stdout is reported by printf */

    app.period = app.cfg.period;
    fprintf(stderr, "attitude-rx: %s at %ld baud 8N1, block %u bytes, method %s, period %g s%s\n",
            app.cfg.port, app.cfg.baud, app.cfg.block_size, rx_method_name(app.cfg.method), app.cfg.period,
            app.cfg.period_set ? "" : " until a BOOT report announces it");
    if (pthread_create(&att_thr, NULL, attitude_thread, &app) != 0
        || pthread_create(&rx_thr, NULL, receiver_thread, &app) != 0) {
        fprintf(stderr, "attitude-rx: cannot start threads\n");
        return RX_EXIT_INTERNAL;
    }
    pthread_join(rx_thr, NULL);
    rx_queue_close(&app.queue); /* the attitude thread finishes what is queued */
    pthread_join(att_thr, NULL);
    if (app.fd >= 0)
        close(app.fd);

    if (g_signal)
        fprintf(stderr, "attitude-rx: stopped by signal %d\n", (int)g_signal);
    fprintf(stderr,
            "attitude-rx: link: syns=%lu blocks_accepted=%lu naks=%lu timeouts=%lu resyncs=%lu "
            "bytes_discarded=%lu\n",
            (unsigned long)app.link.syns, (unsigned long)app.link.blocks_accepted,
            (unsigned long)app.link.naks, (unsigned long)app.link.timeouts, (unsigned long)app.link.resyncs,
            (unsigned long)app.link.bytes_discarded);
    fprintf(stderr,
            "attitude-rx: samples: received=%lu integrated=%lu held=%lu missing=%lu code_errors=%lu "
            "queue_overflows=%lu queue_high_water=%u updates=%lu integrator_errors=%lu port_errors=%lu "
            "reopens=%lu\n",
            app.samples, app.integrated, app.held, app.missing, app.code_errors, app.queue.overflows,
            app.queue.high_water, app.updates, app.integ_errors, app.port_errors, app.reopens);
    fprintf(stderr,
            "attitude-rx: reports: boot=%lu selftest=%lu gave_up=%lu overrun=%lu adc_error=%lu "
            "oversample=%lu block_errors=%lu seq_errors=%lu\n",
            app.reports[ATT_BLOCK_BOOT], app.reports[ATT_BLOCK_SELFTEST], app.reports[ATT_BLOCK_GAVE_UP],
            app.reports[ATT_BLOCK_OVERRUN], app.reports[ATT_BLOCK_ADC_ERROR],
            app.reports[ATT_BLOCK_OVERSAMPLE], app.block_errors, app.seq_errors);
    if (app.queue_missing)
        fprintf(stderr, "attitude-rx: %lu samples were dropped on a full queue (--queue %u)\n",
                app.queue_missing, app.cfg.queue_size);
    rx_queue_destroy(&app.queue);
    return app.out_error ? RX_EXIT_IOERR : RX_EXIT_OK;
}
