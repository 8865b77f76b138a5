/*
 * attitude-rx — the Linux computer's main program (paper sec. 3.3–3.4,
 * Fig. 6): a receiver thread runs the link receiver B on the serial port
 * and puts every gyro sample of every accepted block into a bounded queue;
 * an attitude thread takes samples from the queue, converts ADC codes to
 * angle increments (or rates for rk4), runs the integrator and prints one
 * line per attitude update. Unlike the paper's single shared variable, no
 * sample is lost when the attitude thread is briefly slow; a full queue
 * drops the new sample and counts it (queue_overflows in the statistics).
 *
 * SIGINT/SIGTERM (or --count) stop it cleanly: the receiver stops, the
 * attitude thread finishes the samples already queued, the link and queue
 * statistics go to stderr. A port that disappears (EIO, hang-up) is
 * reported and reopened every --reopen-delay seconds, never spun on.
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
    unsigned long samples;        /* samples received in accepted blocks */
    unsigned long port_errors, reopens;
    unsigned long integrated, updates, integ_errors;
    int out_error; /* stdout failed (closed pipe) */
} rx_app;

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

static void *receiver_thread(void *arg)
{
    rx_app *app = arg;
    att_link_receiver r;
    att_link_receiver_config rc;
    uint8_t block[ATT_LINK_BLOCK_MAX];
    uint8_t buf[256];
    uint32_t seq = 0;

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
                    for (k = 0; k + 6 <= app->cfg.block_size; k += 6) {
                        rx_sample s;
                        int c;
                        for (c = 0; c < 3; c++)
                            s.code[c] = (uint16_t)((block[k + 2 * c] << 8) | block[k + 2 * c + 1]);
                        s.seq = seq++;
                        app->samples++;
                        rx_queue_push(&app->queue, &s);
                    }
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

static int print_update(rx_app *app, const rx_sample *s, const att_real q[4])
{
    att_real e[3], h = 0;
    const double r2d = 180.0 / 3.14159265358979323846;
    const int digits = att_real_size() == 4 ? 9 : 17; /* round-trip precision */
    double t = (double)app->integrated * app->cfg.period;
    int rc;
    if (att_quat_to_euler(q, e) != ATT_OK || att_quat_heading(q, &h) != ATT_OK)
        e[0] = e[1] = e[2] = h = (att_real)0;
    if (app->cfg.format == RX_FORMAT_CSV)
        rc = printf("%.9g,%lu,%u,%u,%u,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g\n", t, (unsigned long)s->seq,
                    s->code[0], s->code[1], s->code[2], digits, (double)q[0], digits, (double)q[1], digits,
                    (double)q[2], digits, (double)q[3], digits, (double)e[0] * r2d, digits,
                    (double)e[1] * r2d, digits, (double)e[2] * r2d, digits, (double)h * r2d);
    else
        rc =
            printf("{\"t\":%.9g,\"n\":%lu,\"codes\":[%u,%u,%u],\"q\":[%.*g,%.*g,%.*g,%.*g],"
                   "\"yaw_deg\":%.*g,\"pitch_deg\":%.*g,\"roll_deg\":%.*g,\"heading_deg\":%.*g}\n",
                   t, (unsigned long)s->seq, s->code[0], s->code[1], s->code[2], digits, (double)q[0], digits,
                   (double)q[1], digits, (double)q[2], digits, (double)q[3], digits, (double)e[0] * r2d,
                   digits, (double)e[1] * r2d, digits, (double)e[2] * r2d, digits, (double)h * r2d);
    if (rc < 0 || fflush(stdout) != 0)
        return -1;
    return 0;
}

static void *attitude_thread(void *arg)
{
    rx_app *app = arg;
    const rx_config *c = &app->cfg;
    att_integ s;
    rx_sample smp;

    if (att_integ_init(&s, c->method, NULL) != ATT_OK) {
        fprintf(stderr, "attitude-rx: integrator rejected method %s\n", rx_method_name(c->method));
        request_stop(app);
        return NULL;
    }
    print_header(app);
    while (rx_queue_pop(&app->queue, &smp) == 0) {
        att_real ch[3], v[3], q[4];
        int i, rc;
        if (c->consumer_delay > 0) {
            struct timespec d;
            d.tv_sec = (time_t)c->consumer_delay;
            d.tv_nsec = (long)((c->consumer_delay - (double)d.tv_sec) * 1e9);
            nanosleep(&d, NULL);
        }
        if (app->out_error || (c->count && app->updates >= c->count))
            continue; /* finished: just drain */
        for (i = 0; i < 3; i++)
            ch[i] = (att_real)(((double)smp.code[i] - c->zero[i]) * c->scale[i]); /* rad/s */
        for (i = 0; i < 3; i++)
            v[i] = (att_real)c->axis_sign[i] * ch[c->axis_src[i]];
        if (c->method == ATT_METHOD_RK4) {
            rc = att_integ_update_rate(&s, v, (att_real)(2.0 * c->period), q);
        } else {
            for (i = 0; i < 3; i++)
                v[i] = (att_real)((double)v[i] * c->period); /* rad per sample interval */
            rc = att_integ_update(&s, v, q);
        }
        if (rc < 0) {
            app->integ_errors++;
            fprintf(stderr, "attitude-rx: sample %lu rejected by the integrator: %s\n",
                    (unsigned long)smp.seq, att_status_str(rc));
            continue;
        }
        app->integrated++;
        if (rc == ATT_INTEG_UPDATED) {
            app->updates++;
            if (print_update(app, &smp, q) != 0) {
                app->out_error = 1;
                request_stop(app);
            } else if (c->count && app->updates >= c->count) {
                request_stop(app);
            }
        }
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
    int help, rc, pipefd[2];
    pthread_t rx_thr, att_thr;
    struct sigaction sa;

    rx_config_defaults(&app.cfg);
    rc = rx_config_parse(&app.cfg, argc, argv, &help, msg, sizeof msg);
    if (help) {
        rx_usage(argv[0], stdout);
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

    fprintf(stderr, "attitude-rx: %s at %ld baud 8N1, block %u bytes, method %s, period %g s\n", app.cfg.port,
            app.cfg.baud, app.cfg.block_size, rx_method_name(app.cfg.method), app.cfg.period);
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
            "attitude-rx: samples: received=%lu integrated=%lu queue_overflows=%lu "
            "queue_high_water=%u updates=%lu integrator_errors=%lu port_errors=%lu reopens=%lu\n",
            app.samples, app.integrated, app.queue.overflows, app.queue.high_water, app.updates,
            app.integ_errors, app.port_errors, app.reopens);
    rx_queue_destroy(&app.queue);
    return app.out_error ? RX_EXIT_IOERR : RX_EXIT_OK;
}
