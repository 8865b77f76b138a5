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
 * Acknowledged => delivered. A block whose checksum matched is answered
 * 0x00 only once all its records are in the queue. When the queue is
 * full the answer waits up to --hold-ms for room (back-pressure: the
 * sender waits), then the block is answered 0xFF and the sender sends it
 * again; nothing acknowledged is ever dropped. With --count, blocks that
 * the count no longer needs are answered 0xFF too, so what was
 * acknowledged is what gets printed.
 *
 * Missing samples are never skipped silently: a loss report (GAVE_UP,
 * OVERRUN, ADC_ERROR), a sample whose code is outside 0..4095 and a gap
 * in the numbering are each filled by holding the last good rate over the
 * missing sample periods, so the time base stays the firmware's; they are
 * counted (held, missing). The sample period comes from the BOOT report
 * unless --period is given.
 *
 * SIGINT/SIGTERM (or --count) stop it within a bounded time whatever is
 * blocked: every wait (port, stdout, stderr, queue, delays) is a poll()
 * that also watches a self-pipe. The receiver stops answering at once,
 * the attitude thread prints every acknowledged record still queued,
 * within RX_STOP_GRACE_MS if stdout is blocked (what it could not print
 * is counted and the exit code says so), and the statistics go to stderr.
 * A port that disappears (EIO, hang-up) is reported and reopened every
 * --reopen-delay seconds, never spun on. docs/attitude-rx.md.
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

/* The link's counters, cumulative, as the wire saw them (what print_statistics
 * prints at the end; with --format jsonl also a {"link":{...}} record at most
 * once per --stats-interval and once at the end). */
#define RX_LINK_RECORD_MS 1000u /* --format jsonl: a {"link":...} record at most once a second */

typedef struct {
    unsigned long syns, blocks, naks, timeouts, resyncs, bytes_discarded;
    unsigned long busy_naks, count_naks, held_answers, unanswered;
    int mode;                    /* RX_LINK_LEGACY / _V2 / _AUTO (nothing heard yet) */
    att_link2_receiver_stats l2; /* link v2's own counters */
} rx_link_live;

typedef struct {
    rx_config cfg;
    rx_queue queue;
    rx_stop stop;                   /* stop requests (signal handler, --count, stdout failure) */
    int fd;                         /* serial port (owned by the receiver thread once started) */
    att_link_receiver_stats link;   /* copied by the receiver thread when it ends */
    att_link2_receiver_stats link2; /* link v2's, likewise */
    int link_used;                  /* RX_LINK_LEGACY / _V2 / _AUTO (nothing heard yet) at the end */
    /* the link counters as they stand (receiver thread writes, attitude thread reads: live_lock) */
    pthread_mutex_t live_lock;
    rx_link_live live;
    struct timespec live_next; /* attitude thread: when the next {"link":...} record is due */
    /* receiver thread */
    unsigned long samples;      /* sample records in acknowledged blocks (good or not) */
    unsigned long acks;         /* 0x00 answers sent: blocks acknowledged */
    unsigned long busy_naks;    /* 0xFF answers for good blocks: the queue stayed full for --hold-ms */
    unsigned long count_naks;   /* 0xFF answers for good blocks --count no longer needs */
    unsigned long held_answers; /* answers that waited for room in the queue */
    unsigned long unanswered;   /* good blocks a stop request left unanswered */
    unsigned long port_errors, reopens;
    /* attitude thread */
    unsigned long integrated, held, missing, updates, integ_errors, code_errors;
    unsigned long pending;     /* sample periods integrated since the last update (rv2/rv3/rk4) */
    unsigned long undelivered; /* acknowledged samples never integrated: output failed or blocked */
    unsigned long lines_lost;  /* attitude lines that could not be written */
    unsigned long reports[ATT_BLOCK_CHANNELS + 1];
    unsigned long acc_records, mag_records; /* aiding records handled (aided streams) */
    unsigned long aid_unused;               /* ... not used: the integrator's, or their sample missing */
    int header_est;                         /* CSV: the estimator whose header was printed (-1: none) */
    unsigned long block_errors, seq_errors;
    double period;   /* s, the sample period in use */
    double t;        /* s, time integrated so far (sample periods, held ones included) */
    int out_error;   /* stdout failed (closed pipe, ...): errno in out_errno */
    int out_errno;   /* the error */
    int out_blocked; /* stdout stayed blocked past the grace time after a stop */
    rx_gnss gnss;    /* --gnss: the input thread and its queue */
    unsigned long gnss_used, gnss_rejected; /* fixes the filter took / refused (ATT_AHRS_F_GNSS_REJECTED) */
    unsigned long gnss_no_vel;              /* fixes without a horizontal velocity (not given) */
    unsigned long gnss_late;                /* fixes the filter's clock could not place (ATT_E_ARG) */
    att_gnss_fix gnss_fix;                  /* the newest fix taken (attitude thread), */
    double gnss_t;                          /* its time of validity on the stream clock (s), */
    int gnss_line;                          /* not yet on an attitude line */
} rx_app;

static const char *const report_names[ATT_BLOCK_CHANNELS + 1] = { "BOOT",    "SELFTEST",  "GAVE_UP",
                                                                  "OVERRUN", "ADC_ERROR", "OVERSAMPLE",
                                                                  "CHANNELS" };

static rx_stop *g_stop = NULL; /* for the signal handler only */
static volatile sig_atomic_t g_signal = 0;

static void on_signal(int sig)
{
    g_signal = sig;
    rx_stop_request(g_stop);
}

static uint16_t now_tick(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint16_t)((unsigned long)ts.tv_sec * 1000UL + (unsigned long)(ts.tv_nsec / 1000000L));
}

/* t = now + ms (CLOCK_MONOTONIC) */
static void after_ms(struct timespec *t, unsigned ms)
{
    clock_gettime(CLOCK_MONOTONIC, t);
    t->tv_sec += (time_t)(ms / 1000u);
    t->tv_nsec += (long)(ms % 1000u) * 1000000L;
    if (t->tv_nsec >= 1000000000L) {
        t->tv_sec++;
        t->tv_nsec -= 1000000000L;
    }
}

static int before(const struct timespec *a, const struct timespec *b)
{
    return a->tv_sec < b->tv_sec || (a->tv_sec == b->tv_sec && a->tv_nsec < b->tv_nsec);
}

enum {
    ANSWER_AS_IS = -2, /* the receiver machine's own byte */
    ANSWER_NONE = -1   /* no answer at all (stopping) */
};

/* Hand out everything the receiver machine wants to send (0xBB, 0x00,
 * 0xFF); the 0x00 of a block it just accepted becomes `ack` (ATT_LINK_ACK,
 * ATT_LINK_NAK, ANSWER_NONE) unless ANSWER_AS_IS. 0, 1 = a stop request
 * came while the port did not take the byte, -1 = port error. */
static int answer(rx_app *app, att_link_receiver *r, int ack)
{
    for (;;) {
        uint8_t out;
        int rc;
        att_link_result res = att_link_receiver_poll(r, now_tick(), &out);
        if (res == ATT_LINK_TIMEOUT)
            continue;
        if (res != ATT_LINK_SEND)
            return 0;
        if (out == (uint8_t)ATT_LINK_ACK && ack != ANSWER_AS_IS) {
            if (ack == ANSWER_NONE)
                continue;
            out = (uint8_t)ack;
        }
        if ((rc = rx_port_write(&app->stop, app->fd, &out, 1)) != 0)
            return rc;
    }
}

static void port_lost(rx_app *app, const char *what, int err)
{
    rx_log(&app->stop, "port %s %s: %s; reopening every %.3g s", app->cfg.port, what,
           err ? strerror(err) : "hang-up", app->cfg.reopen_delay);
    app->port_errors++;
    rx_serial_close(app->fd);
    app->fd = -1;
}

/* The receiver thread's view of what it acknowledged. */
typedef struct {
    att_block_seq seq;     /* numbering of the acknowledged records */
    att_integ shape;       /* a fresh integrator of the method: att_integ_outputs counts lines */
    unsigned long periods; /* sample periods the attitude thread will integrate for them */
    int have_good;         /* a good sample was acknowledged (periods before it are not integrated) */
} rx_acked;

static int is_loss(unsigned kind)
{
    return kind == ATT_BLOCK_GAVE_UP || kind == ATT_BLOCK_OVERRUN || kind == ATT_BLOCK_ADC_ERROR;
}

/* Sample periods the attitude thread integrates for record `it` (the same
 * rules as sample(), bad_record() and hold() below). */
static unsigned long periods_of(const rx_item *it, int *have_good)
{
    if (it->blk.kind == ATT_BLOCK_SAMPLE && it->span.part != ATT_BLOCK_PART_GYR)
        return 0; /* an accelerometer or magnetometer record: part of its sample's period */
    if (it->status == ATT_OK && it->blk.kind == ATT_BLOCK_SAMPLE) {
        *have_good = 1;
        return 1;
    }
    if (!*have_good)
        return 0; /* before the first good sample, missing periods only advance t */
    if (it->status == ATT_BLOCK_E_CODE)
        return 1;
    if (it->status == ATT_OK && is_loss(it->blk.kind))
        return it->span.count;
    return 0;
}

/* --count: are the acknowledged samples already enough for it? (The records still due
 * in the last sample's group belong to its line: never refused.) The filter prints a
 * line per sample, the integrator per update of its method. */
static int count_reached(rx_app *app, const rx_acked *x)
{
    unsigned long failed, n;
    if (app->cfg.count == 0 || x->seq.part != ATT_BLOCK_PART_GYR)
        return 0;
    failed = rx_queue_failed(&app->queue);
    n = x->periods > failed ? x->periods - failed : 0;
    if (rx_estimator_for(app->cfg.estimator, x->seq.channels) == RX_EST_AHRS)
        return n >= app->cfg.count;
    return att_integ_outputs(&x->shape, (size_t)n) >= app->cfg.count;
}

/* Decode and number one record of an accepted block (or a link v2 delivery). */
static void number(att_block_seq *seq, rx_item *it, const uint8_t *raw)
{
    memset(it, 0, sizeof *it);
    memcpy(it->raw, raw, sizeof it->raw);
    it->wall = rx_mono_now();
    it->status =
        att_block_seq_decode(seq, it->raw, &it->blk, &it->span); /* a bad sample still takes its place */
    if (it->status == ATT_BLOCK_E_SEQ) {
        it->seq_status = it->status;
        it->status = ATT_OK;
    }
    it->closes = it->blk.kind == ATT_BLOCK_SAMPLE && seq->part == ATT_BLOCK_PART_GYR;
}

/* Sample records that number a sample (gyro records; in a gyro-only stream every one). */
static unsigned numbers_a_sample(const rx_item *it)
{
    return it->blk.kind == ATT_BLOCK_SAMPLE && it->span.part == ATT_BLOCK_PART_GYR;
}

/* A block passed the checksum (the receiver machine queued 0x00). Decode
 * and number its records and queue them all; only then is the block
 * acknowledged. Returns the answer: ATT_LINK_ACK; ATT_LINK_NAK when the
 * queue stayed full for --hold-ms or --count needs no more samples (the
 * block takes no number); ANSWER_NONE when a stop request came first. */
static int deliver(rx_app *app, rx_acked *x, const uint8_t *block)
{
    rx_item items[RX_RECORDS_MAX];
    att_block_seq seq = x->seq; /* numbered on a copy: a refused block takes no number */
    unsigned long periods = 0;
    int have_good = x->have_good, waited = 0;
    unsigned k, n = 0, samples = 0;
    struct timespec deadline, slice, now;

    if (rx_stop_check(&app->stop)) {
        app->unanswered++;
        return ANSWER_NONE;
    }
    if (count_reached(app, x)) {
        app->count_naks++;
        return ATT_LINK_NAK;
    }
    for (k = 0; k + ATT_BLOCK_SIZE <= app->cfg.block_size; k += ATT_BLOCK_SIZE, n++) {
        number(&seq, &items[n], block + k);
        samples += numbers_a_sample(&items[n]);
        periods += periods_of(&items[n], &have_good);
    }
    after_ms(&deadline, app->cfg.hold_ms);
    for (;;) { /* wait for room in slices of 10 ms, watching for a stop request */
        after_ms(&slice, 10);
        if (before(&deadline, &slice))
            slice = deadline;
        if (rx_queue_push_all(&app->queue, items, n, &slice) == 0)
            break;
        waited = 1;
        if (rx_stop_check(&app->stop)) {
            app->unanswered++;
            return ANSWER_NONE;
        }
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (!before(&now, &deadline)) {
            app->held_answers++;
            app->busy_naks++;
            return ATT_LINK_NAK;
        }
    }
    app->held_answers += (unsigned long)waited;
    x->seq = seq;
    x->periods += periods;
    x->have_good = have_good;
    app->samples += samples;
    app->acks++;
    return ATT_LINK_ACK;
}

/* ---- link v2 (attitude/link2.h): B acknowledges only records it delivered ---- */

/* Records link v2 may deliver now: the queue's room, 0 once --count has enough. */
static uint16_t room2(rx_app *app, rx_acked *x)
{
    unsigned r;
    if (count_reached(app, x))
        return 0;
    r = rx_queue_room(&app->queue);
    return (uint16_t)(r > 0xFFFFu ? 0xFFFFu : r);
}

/* Link v2 delivered n records: decode, number and queue them (the room said they fit)
 * before the ACK that covers them goes out. */
static void deliver2(rx_app *app, rx_acked *x, const uint8_t *out, unsigned n)
{
    rx_item items[ATT_LINK2_SAMPLES_MAX];
    unsigned k, samples = 0;
    unsigned long periods = 0;
    struct timespec now;
    for (k = 0; k < n; k++) {
        number(&x->seq, &items[k], out + ATT_LINK2_RECORD * k);
        samples += numbers_a_sample(&items[k]);
        periods += periods_of(&items[k], &x->have_good);
    }
    clock_gettime(CLOCK_MONOTONIC, &now);
    if (rx_queue_push_all(&app->queue, items, n, &now) != 0)
        rx_log(&app->stop, "internal: %u acknowledged records found no room", n); /* room2 said they fit */
    x->periods += periods;
    app->samples += samples;
    app->acks++;
}

/* Hand out link v2's ACK bytes: 0, 1 = a stop request came while the port did not take a byte,
 * -1 = port error. */
static int answer2(rx_app *app, att_link2_receiver *r)
{
    uint8_t out;
    int rc;
    while (att_link2_receiver_poll(r, &out) == ATT_LINK2_SEND)
        if ((rc = rx_port_write(&app->stop, app->fd, &out, 1)) != 0)
            return rc;
    return 0;
}

/* The counters of the link as they stand: the link machine's, with attitude-rx's
 * own answers (it counts every good block as accepted; some were answered 0xFF). */
static void link_live(const rx_app *app, const att_link_receiver_stats *l, rx_link_live *v)
{
    memset(v, 0, sizeof *v);
    v->syns = (unsigned long)l->syns;
    v->blocks = app->acks;
    v->naks = (unsigned long)l->naks + app->busy_naks + app->count_naks;
    v->timeouts = (unsigned long)l->timeouts;
    v->resyncs = (unsigned long)l->resyncs;
    v->bytes_discarded = (unsigned long)l->bytes_discarded;
    v->busy_naks = app->busy_naks;
    v->count_naks = app->count_naks;
    v->held_answers = app->held_answers;
    v->unanswered = app->unanswered;
}

static void publish_live(rx_app *app, const att_link_receiver_stats *l, const att_link2_receiver_stats *l2,
                         int mode)
{
    rx_link_live v;
    link_live(app, l, &v);
    v.mode = mode;
    v.l2 = *l2;
    pthread_mutex_lock(&app->live_lock);
    app->live = v;
    pthread_mutex_unlock(&app->live_lock);
}

/* --link auto: does a block the legacy receiver accepted decode, every record
 * alone (attitude/block.h), before it names the protocol? A v2 frame's bytes
 * pass the legacy 8-bit checksum by chance (1 in 256 per 0xAA followed by a
 * block's worth of bytes), but a record of random bytes decodes with odds
 * of about 1 in 4096 (a sample's three high nibbles 0; a report's fields
 * narrower still). A block that does not decode is still delivered as on
 * the legacy link (its bad records logged, never integrated); the protocol
 * stays undecided until one that does. */
static int legacy_block_decodes(const uint8_t *block, unsigned size)
{
    att_block b;
    unsigned k;
    for (k = 0; k + ATT_BLOCK_SIZE <= size; k += ATT_BLOCK_SIZE) {
        if (att_block_decode(block + k, &b) != ATT_OK)
            return 0;
    }
    return 1;
}

static void *receiver_thread(void *arg)
{
    rx_app *app = arg;
    att_link_receiver r;
    att_link_receiver_config rc;
    uint8_t block[ATT_LINK_BLOCK_MAX];
    uint8_t buf[256];
    rx_acked x;
    int stop = 0;
    att_link2_receiver r2;
    uint8_t out2[ATT_LINK2_OUT_MAX];
    int mode = app->cfg.link;

    att_block_seq_init(&x.seq);
    x.periods = 0;
    x.have_good = 0;
    att_link_receiver_config_init(&rc, (uint8_t)app->cfg.block_size);
    rc.gap_timeout = (uint16_t)app->cfg.gap_ms;
    if (att_link_receiver_init(&r, &rc, block) != ATT_OK || att_link2_receiver_init(&r2, out2) != ATT_OK
        || att_integ_init(&x.shape, app->cfg.method, NULL) != ATT_OK) {
        rx_log(&app->stop, "link receiver configuration rejected");
        rx_stop_request(&app->stop);
        return NULL;
    }
    while (!stop) {
        struct pollfd p[2];
        int timeout, n;
        uint16_t left;
        if (app->fd < 0) { /* port gone: retry, sleeping in between */
            char msg[RX_MSG_MAX];
            if (rx_stop_wait(&app->stop, app->cfg.reopen_delay))
                break;
            app->fd = rx_serial_open(app->cfg.port, app->cfg.baud, msg, sizeof msg);
            if (app->fd < 0)
                continue;
            rx_log(&app->stop, "port %s reopened", app->cfg.port);
            app->reopens++;
            att_link_receiver_reset(&r);
            att_link2_receiver_reset(&r2);
        }
        left = att_link_receiver_ticks_left(&r, now_tick());
        timeout = (left == ATT_LINK_NO_TIMER || left > 100) ? 100 : (int)left;
        p[0].fd = app->fd;
        p[0].events = POLLIN;
        p[1].fd = app->stop.wake_rd;
        p[1].events = POLLIN;
        p[0].revents = p[1].revents = 0;
        n = poll(p, 2, timeout);
        if (n < 0) {
            if (errno == EINTR)
                continue; /* a signal's byte is in the pipe: the next poll sees it */
            rx_log(&app->stop, "poll: %s", strerror(errno));
            break;
        }
        if ((p[1].revents & POLLIN) && rx_stop_check(&app->stop))
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
            for (i = 0; i < got && !stop; i++) {
                int ack = ANSWER_AS_IS, w;
                if (mode != RX_LINK_LEGACY) {
                    int st2;
                    att_link2_receiver_set_room(&r2, room2(app, &x));
                    st2 = att_link2_receiver_sink(&r2, buf[i]);
                    if (mode == RX_LINK_AUTO && (st2 == ATT_LINK2_FRAME || st2 == ATT_LINK2_DELIVERED)) {
                        mode = RX_LINK_V2; /* this frame is answered below: nothing it carried is lost */
                        rx_log(&app->stop, "protocol: the board speaks link v2");
                        publish_live(app, &r.stats, &r2.stats, mode); /* before its BOOT is checked */
                    }
                    if (mode == RX_LINK_V2) {
                        if (st2 == ATT_LINK2_DELIVERED)
                            deliver2(app, &x, out2, r2.n_out);
                        att_link2_receiver_set_room(&r2, room2(app, &x));
                        w = answer2(app, &r2);
                        if (w < 0) {
                            port_lost(app, "write failed", errno);
                            break;
                        }
                        stop = w > 0 || rx_stop_check(&app->stop);
                        continue;
                    }
                }
                if (att_link_receiver_sink(&r, buf[i], now_tick()) == ATT_LINK_ACCEPTED) {
                    if (mode == RX_LINK_AUTO && legacy_block_decodes(block, app->cfg.block_size)) {
                        mode = RX_LINK_LEGACY; /* this block is delivered below */
                        rx_log(&app->stop, "protocol: the board speaks the legacy protocol");
                        publish_live(app, &r.stats, &r2.stats, mode);
                    }
                    ack = deliver(app, &x, block);
                }
                /* answer at once (the sender waits for 0xBB / 0x00 / 0xFF) */
                w = answer(app, &r, ack);
                if (w < 0) {
                    port_lost(app, "write failed", errno);
                    break;
                }
                stop = w > 0 || ack == ANSWER_NONE;
            }
        } else if (mode == RX_LINK_V2) { /* room may have grown: a window update */
            att_link2_receiver_set_room(&r2, room2(app, &x));
            if ((n = answer2(app, &r2)) != 0) {
                if (n > 0)
                    break;
                port_lost(app, "write failed", errno);
            }
        } else if ((n = answer(app, &r, ANSWER_AS_IS)) != 0) { /* gap timer */
            if (n > 0)
                break;
            port_lost(app, "write failed", errno);
        }
        publish_live(app, &r.stats, &r2.stats, mode);
    }
    app->link = r.stats;
    app->link2 = r2.stats;
    app->link_used = mode;
    publish_live(app, &r.stats, &r2.stats, mode);
    return NULL;
}

static int abandoned(const rx_app *app)
{
    return app->out_error || app->out_blocked;
}

/* Write one line to stdout. An attitude line (update) that cannot be
 * written is counted (lines_lost); a write error (closed pipe) or stdout
 * still blocked when the grace time after a stop ends abandon all output. */
static void out_line(rx_app *app, const char *line, int len, int update)
{
    int rc;
    if (len < 0)
        return;
    if (len >= RX_LINE_MAX)
        len = RX_LINE_MAX - 1; /* snprintf truncated it (cannot happen with these formats) */
    rc = abandoned(app) ? 1 : rx_out_write(&app->stop, 1, line, (size_t)len);
    if (rc == 0)
        return;
    if (update)
        app->lines_lost++;
    if (rc < 0 && !app->out_error) {
        app->out_error = 1;
        app->out_errno = errno;
        rx_stop_request(&app->stop);
    } else if (rc > 0) {
        app->out_blocked = 1;
    }
}

/* JSON Lines record for a report or an error (--format jsonl only); body: ,"key":value... */
static void json_record(rx_app *app, const char *body)
{
    char line[RX_LINE_MAX];
    if (app->cfg.format == RX_FORMAT_JSONL)
        out_line(app, line, snprintf(line, sizeof line, "{\"t\":%.9g,%s}\n", app->t, body), 0);
}

/* CSV: the header of the estimator whose lines follow, before its first line (again
 * when a new stream changes the estimator). */
static void print_header(rx_app *app, rx_estimator e)
{
    static const char h[] = "t,n,code_x,code_y,code_z,q0,q1,q2,q3,yaw_deg,pitch_deg,roll_deg,heading_deg";
    char line[RX_LINE_MAX];
    if (app->cfg.format != RX_FORMAT_CSV || !app->cfg.header || app->header_est == (int)e)
        return;
    app->header_est = (int)e;
    out_line(app, line,
             snprintf(line, sizeof line, "%s%s\n", h,
                      e == RX_EST_AHRS ? ",bias_x_dps,bias_y_dps,bias_z_dps,flags" : ""),
             0);
}

#define RX_R2D (180.0 / 3.14159265358979323846) /* degrees per radian (as computed before: bit for bit) */

/* The fields every attitude line starts with, CSV or JSON (no line end, JSON not closed):
 * t, n, codes, q, Euler angles and heading in degrees (held: JSON). */
static int line_head(const rx_app *app, char *line, size_t size, uint32_t n, const uint16_t code[3],
                     const att_real q[4])
{
    const int digits = att_real_size() == 4 ? 9 : 17; /* round-trip precision */
    att_real e[3], h = 0;
    if (att_quat_to_euler(q, e) != ATT_OK || att_quat_heading(q, &h) != ATT_OK)
        e[0] = e[1] = e[2] = h = (att_real)0;
    if (app->cfg.format == RX_FORMAT_CSV)
        return snprintf(line, size, "%.9g,%lu,%u,%u,%u,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g", app->t,
                        (unsigned long)n, code[0], code[1], code[2], digits, (double)q[0], digits,
                        (double)q[1], digits, (double)q[2], digits, (double)q[3], digits,
                        (double)e[0] * RX_R2D, digits, (double)e[1] * RX_R2D, digits, (double)e[2] * RX_R2D,
                        digits, (double)h * RX_R2D);
    return snprintf(line, size,
                    "{\"t\":%.9g,\"n\":%lu,\"codes\":[%u,%u,%u],\"q\":[%.*g,%.*g,%.*g,%.*g],\"yaw_deg\":%.*g,"
                    "\"pitch_deg\":%.*g,\"roll_deg\":%.*g,\"heading_deg\":%.*g,\"held\":%lu",
                    app->t, (unsigned long)n, code[0], code[1], code[2], digits, (double)q[0], digits,
                    (double)q[1], digits, (double)q[2], digits, (double)q[3], digits, (double)e[0] * RX_R2D,
                    digits, (double)e[1] * RX_R2D, digits, (double)e[2] * RX_R2D, digits, (double)h * RX_R2D,
                    app->held);
}

/* ,"key":[x,y,z] scaled by k (CSV: ,x,y,z); nothing when v is NULL */
static int vec3(const rx_app *app, char *p, size_t len, const char *key, const att_real *v, double k)
{
    const int digits = att_real_size() == 4 ? 9 : 17;
    if (v == NULL)
        return 0;
    if (app->cfg.format == RX_FORMAT_CSV)
        return snprintf(p, len, ",%.*g,%.*g,%.*g", digits, (double)v[0] * k, digits, (double)v[1] * k, digits,
                        (double)v[2] * k);
    return snprintf(p, len, ",\"%s\":[%.*g,%.*g,%.*g]", key, digits, (double)v[0] * k, digits,
                    (double)v[1] * k, digits, (double)v[2] * k);
}

/* JSON: ,"gnss":{...} on the first line after a new fix (docs/gnss.md), else nothing. */
static int gnss_object(rx_app *app, char *p, size_t len)
{
    int n;
    if (!app->gnss_line || app->cfg.format != RX_FORMAT_JSONL)
        return 0;
    app->gnss_line = 0;
    n = rx_gnss_json(p, len, &app->gnss_fix, app->t - app->gnss_t, rx_gnss_source(app->cfg.gnss.kind));
    return n < 0 ? 0 : n;
}

/* An integrator line: the head, then (JSON) the body rate of the newest sample. */
static void print_update(rx_app *app, uint32_t n, const uint16_t code[3], const att_real v[3],
                         const att_real q[4])
{
    char line[RX_LINE_MAX];
    int len;
    print_header(app, RX_EST_INTEGRATOR);
    len = line_head(app, line, sizeof line, n, code, q);
    if (app->cfg.format != RX_FORMAT_CSV) {
        len += vec3(app, line + len, sizeof line - (size_t)len, "rate_dps", v, RX_R2D);
        len += gnss_object(app, line + len, sizeof line - (size_t)len);
    }
    len +=
        snprintf(line + len, sizeof line - (size_t)len, "%s\n", app->cfg.format == RX_FORMAT_CSV ? "" : "}");
    out_line(app, line, len, 1);
}

/* The filter's flags by name (attitude/ahrs.h, ATT_AHRS_F_*). */
static const struct {
    int bit;
    const char *name;
} flag_names[] = {
    { ATT_AHRS_F_OVERRANGE, "overrange" },         { ATT_AHRS_F_REST, "rest" },
    { ATT_AHRS_F_ACC_REJECTED, "acc_rejected" },   { ATT_AHRS_F_MAG_DISTURBED, "mag_disturbed" },
    { ATT_AHRS_F_MAG_RELEARNED, "mag_relearned" }, { ATT_AHRS_F_NO_HEADING, "no_heading" },
    { ATT_AHRS_F_GNSS_AIDED, "gnss_aided" },       { ATT_AHRS_F_GNSS_REJECTED, "gnss_rejected" }
};

/* ,"flags":["rest",...] */
static int json_flags(char *p, size_t len, int flags)
{
    size_t i;
    int n = snprintf(p, len, ",\"flags\":[");
    for (i = 0; i < sizeof flag_names / sizeof flag_names[0]; i++)
        if ((flags & flag_names[i].bit) && n >= 0 && (size_t)n < len)
            n += snprintf(p + n, len - (size_t)n, "%s\"%s\"", p[n - 1] == '[' ? "" : ",", flag_names[i].name);
    if (n >= 0 && (size_t)n < len)
        n += snprintf(p + n, len - (size_t)n, "]");
    return n;
}

/* What the filter adds to a line: its gyro-bias estimate and flags, the sample's aiding vectors. */
typedef struct {
    att_real bias[3];          /* rad/s */
    att_real cov[9];           /* attitude covariance, rad², ENU, row-major (att_ahrs_covariance) */
    int flags;                 /* ATT_AHRS_F_* */
    const att_real *acc, *mag; /* m/s², µT, or NULL: not in this sample */
} rx_filter_out;

/* ,"cov":[9 numbers, rad², row-major],"heading_sigma_deg":…,"heading_observable":true|false */
static int json_uncertainty(char *p, size_t len, const rx_filter_out *f)
{
    const int digits = att_real_size() == 4 ? 9 : 17;
    const att_real *c = f->cov;
    double hs = c[8] > 0 ? sqrt((double)c[8]) * RX_R2D : 0.0;
    return snprintf(p, len,
                    ",\"cov\":[%.*g,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g,%.*g],\"heading_sigma_deg\":%.*g,"
                    "\"heading_observable\":%s",
                    digits, (double)c[0], digits, (double)c[1], digits, (double)c[2], digits, (double)c[3],
                    digits, (double)c[4], digits, (double)c[5], digits, (double)c[6], digits, (double)c[7],
                    digits, (double)c[8], digits, hs, (f->flags & ATT_AHRS_F_NO_HEADING) ? "false" : "true");
}

/* A filter line: the head, then the rate, bias (°/s), flags, the covariance with the heading's
 * 1σ and observability, acc (m/s²) and mag (µT) in JSON; the bias (°/s) and the flag bits in CSV. */
static void print_filter(rx_app *app, uint32_t n, const uint16_t code[3], const att_real v[3],
                         const att_real q[4], const rx_filter_out *f)
{
    char line[RX_LINE_MAX];
    int w;
    print_header(app, RX_EST_AHRS);
    w = line_head(app, line, sizeof line, n, code, q);
    if (app->cfg.format == RX_FORMAT_CSV) {
        w += vec3(app, line + w, sizeof line - (size_t)w, "bias_dps", f->bias, RX_R2D);
        w += snprintf(line + w, sizeof line - (size_t)w, ",%d\n", f->flags);
        out_line(app, line, w, 1);
        return;
    }
    w += vec3(app, line + w, sizeof line - (size_t)w, "rate_dps", v, RX_R2D);
    w += vec3(app, line + w, sizeof line - (size_t)w, "bias_dps", f->bias, RX_R2D);
    w += json_flags(line + w, sizeof line - (size_t)w, f->flags);
    w += json_uncertainty(line + w, sizeof line - (size_t)w, f);
    w += vec3(app, line + w, sizeof line - (size_t)w, "acc_ms2", f->acc, 1.0);
    w += vec3(app, line + w, sizeof line - (size_t)w, "mag_ut", f->mag, 1.0);
    w += gnss_object(app, line + w, sizeof line - (size_t)w);
    w += snprintf(line + w, sizeof line - (size_t)w, "}\n");
    out_line(app, line, w, 1);
}

/* The sample whose accelerometer and magnetometer records are still due (the filter). */
typedef struct {
    int open;         /* its gyro record came; the group is not complete */
    uint32_t n;       /* its number */
    att_real gyr[3];  /* rad/s */
    uint16_t code[3]; /* its gyro codes */
    att_real acc[3];  /* m/s² */
    att_real mag[3];  /* µT */
    int has_acc, has_mag;
} rx_group;

/* The attitude thread's estimator state. */
typedef struct {
    att_integ integ;
    att_sensor gyro; /* codes -> body rate (--gyro-zero, --gyro-scale, --axes) */
    att_sensor acc;  /* codes -> specific force, m/s² (acc-*) */
    att_sensor mag;  /* codes -> field, µT (mag-*) */
    att_ahrs ahrs;   /* the filter (initialized when a stream first needs it) */
    int ahrs_ready;
    rx_estimator est;    /* this stream's estimator, once est_known */
    int est_known;       /* resolved at the stream's first sample */
    unsigned channels;   /* this stream's channel set (CHANNELS; a BOOT: gyro only) */
    uint8_t oversample;  /* conversions per sample word: 1, or the stream's OVERSAMPLE */
    att_real rate[3];    /* body rate of the last good sample, rad/s */
    uint16_t code[3];    /* its codes */
    int have_rate;       /* a good sample has been integrated */
    rx_group grp;        /* the filter's sample waiting for its group */
    rx_gnss_clock clock; /* the board stream's clock against CLOCK_MONOTONIC (GNSS alignment) */
    unsigned gnss_given; /* fixes given to the filter since its last update */
} rx_att;

/* A fix at stream time t to the filter (its clock: att_ahrs_time, the sum of its steps). */
static void gnss_to_filter(rx_app *app, rx_att *a, const att_gnss_fix *fix, double t)
{
    att_ahrs_vel v;
    double tf = (double)att_ahrs_time(&a->ahrs) + (t - app->t);
    int rc;
    if (att_ahrs_vel_from_fix(fix, (att_real)tf, &v) != ATT_OK) {
        app->gnss_no_vel++;
        return;
    }
    rc = att_ahrs_update_vel(&a->ahrs, &v);
    if (rc == ATT_OK) {
        a->gnss_given++;
        return;
    }
    if (app->gnss_late++ == 0)
        rx_log(&app->stop, "gnss: a fix valid at t=%.3f s refused by the filter: %s (counted in late=)", t,
               att_status_str(rc));
}

/* Every fix due by the end of the coming sample period, in time order: to the filter
 * (`to_filter`: the filter runs this stream), the newest onto the next attitude line. */
static void gnss_take(rx_app *app, rx_att *a, int to_filter)
{
    rx_gnss_item it;
    double horizon = app->t + app->period;
    if (app->cfg.gnss.kind == RX_GNSS_OFF)
        return; /* no --gnss: the sample path as without GNSS */
    while (a->clock.known && rx_gnss_peek(&app->gnss, &it)) {
        double t = rx_gnss_clock_time(&a->clock, it.wall, app->cfg.gnss_latency);
        if (t > horizon)
            break; /* the board has not got there yet */
        rx_gnss_pop(&app->gnss);
        app->gnss_fix = it.fix;
        app->gnss_t = t;
        app->gnss_line = 1;
        if (to_filter && a->ahrs_ready)
            gnss_to_filter(app, a, &it.fix, t);
    }
}

/* The update after fixes were given says whether it took them (ATT_AHRS_F_GNSS_REJECTED). */
static void gnss_verdict(rx_app *app, rx_att *a, int rc)
{
    if (a->gnss_given == 0)
        return;
    if (rc == ATT_OK && (att_ahrs_flags(&a->ahrs) & ATT_AHRS_F_GNSS_REJECTED))
        app->gnss_rejected += a->gnss_given;
    else if (rc == ATT_OK)
        app->gnss_used += a->gnss_given;
    a->gnss_given = 0;
}

static int finished(const rx_app *app)
{
    return abandoned(app) || (app->cfg.count && app->updates >= app->cfg.count);
}

/* Integrate one sample period (number n) at body rate v; codes for the output line. */
static void integrate(rx_app *app, rx_att *a, uint32_t n, const att_real v[3], const uint16_t code[3])
{
    const rx_config *c = &app->cfg;
    att_real d[3], q[4];
    int i, rc;
    gnss_take(app, a, 0);
    if (c->method == ATT_METHOD_RK4) {
        rc = att_integ_update_rate(&a->integ, v, (att_real)(2.0 * app->period), q);
    } else {
        for (i = 0; i < 3; i++)
            d[i] = (att_real)((double)v[i] * app->period); /* rad per sample interval */
        rc = att_integ_update(&a->integ, d, q);
    }
    if (rc < 0) {
        app->integ_errors++;
        rx_queue_count_failed(&app->queue); /* the receiver's --count accounting */
        rx_log(&app->stop, "sample %lu rejected by the integrator: %s", (unsigned long)n, att_status_str(rc));
        return;
    }
    app->t += app->period;
    if (rc != ATT_INTEG_UPDATED) {
        app->pending++;
        return;
    }
    app->pending = 0;
    if (c->count && app->updates >= c->count)
        return; /* past --count (the rest of a block of several samples): integrated, not printed */
    app->updates++;
    print_update(app, n, code, v, q);
    if (c->count && app->updates == c->count)
        rx_stop_request(&app->stop);
}

/* One sample period through the filter: gyr (rad/s), acc, mag (or NULL). */
static void filter(rx_app *app, rx_att *a, uint32_t n, const att_real v[3], const uint16_t code[3],
                   const att_real *acc, const att_real *mag)
{
    att_real q[4];
    rx_filter_out f;
    int rc;
    gnss_take(app, a, 1);
    rc = att_ahrs_update(&a->ahrs, v, acc, mag, (att_real)app->period, q);
    gnss_verdict(app, a, rc);
    if (rc != ATT_OK) {
        app->integ_errors++;
        rx_queue_count_failed(&app->queue); /* the receiver's --count accounting */
        rx_log(&app->stop, "sample %lu rejected by the filter: %s", (unsigned long)n, att_status_str(rc));
        return;
    }
    app->t += app->period;
    if (app->cfg.count && app->updates >= app->cfg.count)
        return; /* past --count: filtered, not printed */
    app->updates++;
    att_ahrs_bias(&a->ahrs, f.bias);
    att_ahrs_covariance(&a->ahrs, f.cov, NULL);
    f.flags = att_ahrs_flags(&a->ahrs);
    f.acc = acc;
    f.mag = mag;
    print_filter(app, n, code, v, q, &f);
    if (app->cfg.count && app->updates == app->cfg.count)
        rx_stop_request(&app->stop);
}

/* The estimator of this stream, chosen at its first sample (or missing period). */
static rx_estimator estimator(rx_app *app, rx_att *a)
{
    rx_estimator e;
    if (a->est_known)
        return a->est;
    e = rx_estimator_for(app->cfg.estimator, a->channels);
    if (e == RX_EST_AHRS && !a->ahrs_ready) {
        if (att_ahrs_init(&a->ahrs, &app->cfg.ahrs, NULL) == ATT_OK)
            a->ahrs_ready = 1;
        else
            e = RX_EST_INTEGRATOR; /* not reached: the settings were checked when read */
    }
    if (app->cfg.estimator == RX_EST_AHRS && e != RX_EST_AHRS)
        rx_log(&app->stop,
               "warning: --estimator ahrs, but the stream has no accelerometer (%s): integrating "
               "the gyros",
               a->channels & ATT_BLOCK_CH_GYR ? "gyro only" : "no CHANNELS report");
    rx_log(&app->stop, "estimator: %s", rx_estimator_name(e));
    a->est = e;
    a->est_known = 1;
    return e;
}

/* One sample period through this stream's estimator (the held rate: acc, mag NULL). */
static void step(rx_app *app, rx_att *a, uint32_t n, const att_real v[3], const uint16_t code[3],
                 const att_real *acc, const att_real *mag)
{
    if (estimator(app, a) == RX_EST_AHRS)
        filter(app, a, n, v, code, acc, mag);
    else
        integrate(app, a, n, v, code);
}

/* The group of the open sample is complete (or cut short): filter it. */
static void close_group(rx_app *app, rx_att *a)
{
    rx_group *g = &a->grp;
    if (!g->open)
        return;
    g->open = 0;
    filter(app, a, g->n, g->gyr, g->code, g->has_acc ? g->acc : NULL, g->has_mag ? g->mag : NULL);
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
        rx_log(&app->stop, "%s missing (%s) before the first sample: no rate to hold", which, why);
        app->t += (double)n * app->period;
        return;
    }
    rx_log(&app->stop, "%s missing (%s): holding the last rate over %lu sample period%s", which, why,
           (unsigned long)n, n == 1u ? "" : "s");
    for (k = 0; k < n && !finished(app); k++) {
        app->held++;
        step(app, a, first + k, a->rate, a->code, NULL, NULL);
    }
}

/* A good sample: codes -> body rate (calibration, axes: att_sensor) -> the estimator
 * (the filter: once its group's accelerometer and magnetometer records are in). */
static void sample(rx_app *app, rx_att *a, const rx_item *it)
{
    int i;
    if (att_sensor_convert(&a->gyro, it->blk.code, a->oversample, a->rate) != ATT_OK)
        return; /* not reached: the tracker checked the codes against the stream's limit */
    for (i = 0; i < 3; i++)
        a->code[i] = it->blk.code[i];
    a->have_rate = 1;
    app->integrated++;
    rx_gnss_clock_sample(&a->clock, it->wall, app->t + app->period);
    if (estimator(app, a) != RX_EST_AHRS) {
        integrate(app, a, it->span.first, a->rate, a->code);
        return;
    }
    memset(&a->grp, 0, sizeof a->grp);
    a->grp.open = 1;
    a->grp.n = it->span.first;
    memcpy(a->grp.gyr, a->rate, sizeof a->grp.gyr);
    memcpy(a->grp.code, a->code, sizeof a->grp.code);
    if (it->closes)
        close_group(app, a);
}

/* An accelerometer or magnetometer record: into its sample's group (the filter), or counted. */
static void aiding(rx_app *app, rx_att *a, const rx_item *it)
{
    const int is_acc = it->span.part == ATT_BLOCK_PART_ACC;
    rx_group *g = &a->grp;
    att_real *v = is_acc ? g->acc : g->mag;
    char body[RX_MSG_MAX];
    if (is_acc)
        app->acc_records++;
    else
        app->mag_records++;
    if (it->status != ATT_OK) { /* a code above the stream's limit: this sample goes without it */
        app->code_errors++;
        rx_log(&app->stop, "%s record of sample %lu rejected: code out of range (%u, %u, %u)",
               is_acc ? "accelerometer" : "magnetometer", (unsigned long)it->span.first, it->blk.code[0],
               it->blk.code[1], it->blk.code[2]);
        snprintf(body, sizeof body, "\"error\":\"code\",\"n\":%lu,\"part\":\"%s\",\"codes\":[%u,%u,%u]",
                 (unsigned long)it->span.first, is_acc ? "acc" : "mag", it->blk.code[0], it->blk.code[1],
                 it->blk.code[2]);
        json_record(app, body);
    } else if (g->open && g->n == it->span.first
               && att_sensor_convert(is_acc ? &a->acc : &a->mag, it->blk.code, a->oversample, v) == ATT_OK) {
        if (is_acc)
            g->has_acc = 1;
        else
            g->has_mag = 1;
    } else {
        app->aid_unused++; /* the integrator's stream, or its sample's gyro record was missing */
    }
    if (it->closes)
        close_group(app, a);
}

/* --format jsonl: the link's counters as a {"link":{...}} record (cumulative). */
static void link_record(rx_app *app)
{
    char body[RX_LINE_MAX / 2];
    rx_link_live v;
    pthread_mutex_lock(&app->live_lock);
    v = app->live;
    pthread_mutex_unlock(&app->live_lock);
    if (v.mode == RX_LINK_V2) /* link v2's counters; "blocks" = deliveries, as on the legacy link */
        snprintf(body, sizeof body,
                 "\"link\":{\"protocol\":\"v2\",\"blocks\":%lu,\"frames\":%lu,\"bad_frames\":%lu,"
                 "\"records\":%lu,\"duplicates\":%lu,\"gaps\":%lu,\"refused\":%lu,\"syns\":%lu,"
                 "\"no_session\":%lu,\"acks\":%lu,\"bytes_discarded\":%lu}",
                 v.blocks, (unsigned long)v.l2.frames, (unsigned long)v.l2.bad_frames,
                 (unsigned long)v.l2.records, (unsigned long)v.l2.duplicates, (unsigned long)v.l2.gaps,
                 (unsigned long)v.l2.refused, (unsigned long)v.l2.syns, (unsigned long)v.l2.no_session,
                 (unsigned long)v.l2.acks, (unsigned long)v.l2.bytes_discarded);
    else
        snprintf(body, sizeof body,
                 "\"link\":{\"syns\":%lu,\"blocks\":%lu,\"naks\":%lu,\"timeouts\":%lu,\"resyncs\":%lu,"
                 "\"bytes_discarded\":%lu,\"busy_naks\":%lu,\"count_naks\":%lu,\"held_answers\":%lu,"
                 "\"unanswered\":%lu}",
                 v.syns, v.blocks, v.naks, v.timeouts, v.resyncs, v.bytes_discarded, v.busy_naks,
                 v.count_naks, v.held_answers, v.unanswered);
    json_record(app, body);
}

/* A link record at most every RX_LINK_RECORD_MS, written between attitude lines. */
static void link_record_due(rx_app *app)
{
    struct timespec now;
    if (app->cfg.format != RX_FORMAT_JSONL)
        return;
    clock_gettime(CLOCK_MONOTONIC, &now);
    if (before(&now, &app->live_next))
        return;
    after_ms(&app->live_next, RX_LINK_RECORD_MS);
    link_record(app);
}

/* Warn when a sample every `period` s cannot fit the line: the legacy
 * handshake's capacity (rx_rate_check); link v2 carries about twice that
 * (docs/link.md) and is not checked; `mode` RX_LINK_AUTO: nothing heard yet. */
static void rate_check(rx_app *app, double period, int mode)
{
    char msg[RX_MSG_MAX];
    if (mode != RX_LINK_V2 && rx_rate_check(app->cfg.baud, app->cfg.block_size, period, msg, sizeof msg))
        rx_log(&app->stop, "warning: %s%s", msg,
               mode == RX_LINK_AUTO
                   ? " (if it speaks the legacy protocol; link v2 carries about twice as much)"
                   : "");
}

/* The protocol the link uses: --link, or with auto the one heard (RX_LINK_AUTO: none yet). */
static int link_mode(rx_app *app)
{
    int mode = app->cfg.link;
    if (mode == RX_LINK_AUTO) {
        pthread_mutex_lock(&app->live_lock);
        mode = app->live.mode;
        pthread_mutex_unlock(&app->live_lock);
    }
    return mode;
}

static void boot(rx_app *app, const att_block *b)
{
    char body[RX_MSG_MAX];
    double p = (double)b->period_ticks / (double)ATT_BLOCK_TICK_HZ;
    long baud = (long)b->baud_div * ATT_BLOCK_BAUD_UNIT;
    rx_log(&app->stop, "BOOT: block format %u, sample period %u ticks = %g s, %ld baud", b->version,
           b->period_ticks, p, baud);
    if (!app->cfg.period_set) {
        app->period = p;
    } else if (fabs(p - app->cfg.period) > 1e-9 * p) {
        rx_log(&app->stop,
               "warning: the board samples every %g s (BOOT) but --period %g s was given: integrating "
               "with %g s",
               p, app->cfg.period, app->cfg.period);
    }
    if (baud != app->cfg.baud)
        rx_log(&app->stop, "warning: the board announces %ld baud, the port runs at %ld", baud,
               app->cfg.baud);
    rate_check(app, p, link_mode(app)); /* the board's real rate against this port's line */
    snprintf(body, sizeof body,
             "\"report\":\"BOOT\",\"version\":%u,\"period_ticks\":%u,\"period_s\":%.9g,\"baud\":%ld,"
             "\"period_used_s\":%.9g",
             b->version, b->period_ticks, p, baud, app->period);
    json_record(app, body);
}

static void channels(rx_app *app, rx_att *a, const att_block *b)
{
    char body[RX_MSG_MAX];
    a->channels = b->channels;
    a->est_known = 0;
    rx_log(&app->stop, "CHANNELS: board %u, gyro%s%s, accelerometer every %u, magnetometer every %u sample%s",
           b->board, b->channels & ATT_BLOCK_CH_ACC ? " + accelerometer" : "",
           b->channels & ATT_BLOCK_CH_MAG ? " + magnetometer" : "", b->acc_every, b->mag_every,
           b->mag_every == 1u ? "" : "s");
    snprintf(body, sizeof body,
             "\"report\":\"CHANNELS\",\"board\":%u,\"channels\":%u,\"acc_every\":%u,\"mag_every\":%u",
             b->board, b->channels, b->acc_every, b->mag_every);
    json_record(app, body);
}

static void report(rx_app *app, rx_att *a, const rx_item *it)
{
    const att_block *b = &it->blk;
    char body[RX_MSG_MAX], scan[32] = "";
    const char *name = report_names[b->kind];
    app->reports[b->kind]++;
    if (it->seq_status == ATT_BLOCK_E_SEQ && it->span.part != ATT_BLOCK_PART_GYR) {
        app->seq_errors++; /* its sample went to the estimator with what had come (handle()) */
        rx_log(&app->stop,
               "%s inside a sample's group: its %s record never came (the sample is used without it)", name,
               it->span.part == ATT_BLOCK_PART_ACC ? "accelerometer" : "magnetometer");
    }
    if (b->kind == ATT_BLOCK_BOOT) {
        a->oversample = 1;              /* a new stream: plain codes until an OVERSAMPLE report, */
        a->channels = ATT_BLOCK_CH_GYR; /* gyro only until a CHANNELS report */
        a->est_known = 0;               /* its estimator chosen at its first sample */
        boot(app, b);
        return;
    }
    if (b->kind == ATT_BLOCK_CHANNELS) {
        channels(app, a, b);
        return;
    }
    if (b->kind == ATT_BLOCK_OVERSAMPLE) {
        a->oversample = b->oversample;
        rx_log(&app->stop, "OVERSAMPLE: each sample word is the sum of %u conversions", b->oversample);
        snprintf(body, sizeof body, "\"report\":\"OVERSAMPLE\",\"n\":%u", b->oversample);
        json_record(app, body);
        return;
    }
    if (b->kind == ATT_BLOCK_SELFTEST) {
        rx_log(&app->stop, "SELFTEST failed: status %d, code %u, attempt %u", b->status, b->bad_code,
               b->attempt);
        snprintf(body, sizeof body, "\"report\":\"SELFTEST\",\"status\":%d,\"bad_code\":%u,\"attempt\":%u",
                 b->status, b->bad_code, b->attempt);
        json_record(app, body);
        return;
    }
    /* a loss report: span = the samples missing here (an unreported gap included) */
    if (it->seq_status == ATT_BLOCK_E_SEQ && it->span.slip != 0) {
        app->seq_errors++;
        rx_log(&app->stop, "%s for sample %u, but %ld sample%s %s: numbering follows the report", name,
               b->first, (long)(it->span.slip < 0 ? -it->span.slip : it->span.slip),
               (it->span.slip == 1 || it->span.slip == -1) ? "" : "s",
               it->span.slip > 0 ? "vanished unreported before it" : "were counted twice");
    }
    if (b->kind == ATT_BLOCK_ADC_ERROR)
        snprintf(scan, sizeof scan, " (scan status %d)", b->status);
    rx_log(&app->stop, "%s: %u sample%s lost at sample %u%s", name, b->count, b->count == 1u ? "" : "s",
           b->first, scan);
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
        rx_log(&app->stop, "sample %lu rejected: code out of 0..%d (%u, %u, %u)",
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
        rx_log(&app->stop, "BOOT %s ignored: block format %u, this program reads format %d", hex,
               it->blk.version, ATT_BLOCK_VERSION);
    else
        rx_log(&app->stop, "record %s ignored: %s", hex,
               it->status == ATT_BLOCK_E_KIND ? "unknown report kind" : "report field out of range");
    snprintf(body, sizeof body, "\"error\":\"%s\",\"raw\":\"%s\"",
             it->status == ATT_BLOCK_E_KIND ? "kind" : "field", hex);
    json_record(app, body);
}

/* One record, in stream order. A filter's sample waits for its group: a record that
 * is not one of its aiding records (a report, the next sample) closes it first. */
static void handle(rx_app *app, rx_att *a, const rx_item *it)
{
    if (it->blk.kind == ATT_BLOCK_SAMPLE && it->span.part != ATT_BLOCK_PART_GYR
        && (it->status == ATT_OK || it->status == ATT_BLOCK_E_CODE)) {
        aiding(app, a, it);
        return;
    }
    close_group(app, a);
    if (it->status != ATT_OK)
        bad_record(app, a, it);
    else if (it->blk.kind == ATT_BLOCK_SAMPLE)
        sample(app, a, it);
    else
        report(app, a, it);
}

static void *attitude_thread(void *arg)
{
    rx_app *app = arg;
    const rx_config *c = &app->cfg;
    rx_att a;
    rx_item it;

    memset(&a, 0, sizeof a);
    a.oversample = 1;
    a.channels = ATT_BLOCK_CH_GYR;
    if (rx_sensor_init(&c->gyro, &a.gyro) != ATT_OK || rx_sensor_init(&c->acc, &a.acc) != ATT_OK
        || rx_sensor_init(&c->mag, &a.mag) != ATT_OK) {
        rx_log(&app->stop, "sensor calibration rejected (gyro-*, acc-*, mag-*)"); /* checked when read */
        rx_stop_request(&app->stop);
        return NULL;
    }
    if (att_integ_init(&a.integ, c->method, NULL) != ATT_OK) {
        rx_log(&app->stop, "integrator rejected method %s", rx_method_name(c->method));
        rx_stop_request(&app->stop);
        return NULL;
    }
    /* every record in the queue was acknowledged: each is handled, also after a stop request */
    while (rx_queue_pop(&app->queue, &it) == 0) {
        if (abandoned(app)) { /* stdout failed or stayed blocked: count what cannot be printed */
            if (it.status == ATT_OK && numbers_a_sample(&it))
                app->undelivered++;
            continue;
        }
        if (c->consumer_delay > 0)
            (void)rx_stop_wait(&app->stop, c->consumer_delay); /* a diagnostic: not once stopping */
        handle(app, &a, &it);
        link_record_due(app);
    }
    close_group(app, &a); /* a group the stream ended in (a stop): its sample with what came */
    return NULL;
}

static void gnss_banner(rx_app *app)
{
    const rx_gnss_spec *g = &app->cfg.gnss;
    if (g->kind == RX_GNSS_SERIAL)
        rx_log(&app->stop, "gnss: %s at %ld baud 8N1 (NMEA 0183 / UBX NAV-PVT), latency %g s", g->path,
               g->baud, app->cfg.gnss_latency);
    else if (g->kind == RX_GNSS_GPSD)
        rx_log(&app->stop, "gnss: gpsd at %s:%s, latency %g s", g->host, g->service, app->cfg.gnss_latency);
}

/* The end-of-run "gnss:" line: what the input read, what the filter did with it, the parser's
 * (serial) or gpsd's (reports) counters. */
static void gnss_statistics(rx_app *app)
{
    rx_gnss_counts n;
    char tail[RX_MSG_MAX];
    if (app->cfg.gnss.kind == RX_GNSS_OFF)
        return;
    n = rx_gnss_counters(&app->gnss);
    if (app->cfg.gnss.kind == RX_GNSS_GPSD)
        snprintf(tail, sizeof tail, "reports=%lu", n.reports);
    else
        snprintf(tail, sizeof tail,
                 "bytes=%lu nmea=%lu ubx=%lu bad_checksum=%lu overruns=%lu truncated=%lu bad_field=%lu "
                 "ignored=%lu bytes_skipped=%lu",
                 (unsigned long)n.parser.bytes, (unsigned long)n.parser.nmea_accepted,
                 (unsigned long)n.parser.ubx_accepted, (unsigned long)n.parser.bad_checksum,
                 (unsigned long)n.parser.overruns, (unsigned long)n.parser.truncated,
                 (unsigned long)n.parser.bad_field, (unsigned long)n.parser.ignored,
                 (unsigned long)n.parser.bytes_skipped);
    rx_log(&app->stop,
           "gnss: source=%s fixes=%lu used=%lu rejected=%lu no_velocity=%lu late=%lu dropped=%lu lost=%lu %s",
           rx_gnss_source(app->cfg.gnss.kind), n.fixes, app->gnss_used, app->gnss_rejected, app->gnss_no_vel,
           app->gnss_late, n.dropped, n.lost, tail);
}

static void print_statistics(rx_app *app)
{
    rx_link_live v; /* what went on the wire (link_live) */
    link_live(app, &app->link, &v);
    if (g_signal)
        rx_log(&app->stop, "stopped by signal %d", (int)g_signal);
    if (app->link_used != RX_LINK_V2)
        rx_log(&app->stop,
               "link: syns=%lu blocks_accepted=%lu naks=%lu timeouts=%lu resyncs=%lu bytes_discarded=%lu "
               "busy_naks=%lu count_naks=%lu held_answers=%lu unanswered=%lu",
               v.syns, v.blocks, v.naks, v.timeouts, v.resyncs, v.bytes_discarded, v.busy_naks, v.count_naks,
               v.held_answers, v.unanswered);
    if (app->link_used != RX_LINK_LEGACY)
        rx_log(&app->stop,
               "link2: frames=%lu bad_frames=%lu records=%lu duplicates=%lu gaps=%lu refused=%lu syns=%lu "
               "no_session=%lu acks=%lu bytes_discarded=%lu",
               (unsigned long)app->link2.frames, (unsigned long)app->link2.bad_frames,
               (unsigned long)app->link2.records, (unsigned long)app->link2.duplicates,
               (unsigned long)app->link2.gaps, (unsigned long)app->link2.refused,
               (unsigned long)app->link2.syns, (unsigned long)app->link2.no_session,
               (unsigned long)app->link2.acks, (unsigned long)app->link2.bytes_discarded);
    rx_log(&app->stop,
           "samples: received=%lu integrated=%lu held=%lu missing=%lu code_errors=%lu pending=%lu "
           "undelivered=%lu lines_lost=%lu queue_high_water=%u updates=%lu integrator_errors=%lu "
           "port_errors=%lu reopens=%lu",
           app->samples, app->integrated, app->held, app->missing, app->code_errors, app->pending,
           app->undelivered, app->lines_lost, app->queue.high_water, app->updates, app->integ_errors,
           app->port_errors, app->reopens);
    rx_log(&app->stop,
           "reports: boot=%lu selftest=%lu gave_up=%lu overrun=%lu adc_error=%lu oversample=%lu "
           "block_errors=%lu seq_errors=%lu",
           app->reports[ATT_BLOCK_BOOT], app->reports[ATT_BLOCK_SELFTEST], app->reports[ATT_BLOCK_GAVE_UP],
           app->reports[ATT_BLOCK_OVERRUN], app->reports[ATT_BLOCK_ADC_ERROR],
           app->reports[ATT_BLOCK_OVERSAMPLE], app->block_errors, app->seq_errors);
    if (app->reports[ATT_BLOCK_CHANNELS])
        rx_log(&app->stop, "aiding: channels=%lu acc_records=%lu mag_records=%lu unused=%lu",
               app->reports[ATT_BLOCK_CHANNELS], app->acc_records, app->mag_records, app->aid_unused);
    gnss_statistics(app);
    if (app->undelivered || app->lines_lost)
        rx_log(&app->stop, "%lu acknowledged sample%s not integrated and %lu attitude line%s not printed: %s",
               app->undelivered, app->undelivered == 1 ? "" : "s", app->lines_lost,
               app->lines_lost == 1 ? "" : "s",
               app->out_error ? strerror(app->out_errno) : "stdout stayed blocked after the stop");
}

int main(int argc, char **argv)
{
    static rx_app app; /* large (queue): not on the stack */
    char msg[RX_MSG_MAX];
    int rc;
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
        printf("attitude-rx %s (libattitude, att_real = %s, gpsd support: %s)\n", RX_VERSION,
               att_real_size() == 4 ? "float" : "double", rx_gpsd_built ? "yes (libgps)" : "no");
        return RX_EXIT_OK;
    }
    if (rc != 0) {
        fprintf(stderr, "attitude-rx: %s\n", msg);
        return rc;
    }
    if (rx_stop_init(&app.stop) != 0 || rx_queue_init(&app.queue, app.cfg.queue_size) != 0
        || pthread_mutex_init(&app.live_lock, NULL) != 0) {
        fprintf(stderr, "attitude-rx: cannot set up threads: %s\n", strerror(errno));
        return RX_EXIT_INTERNAL;
    }
    /* from here on all output goes through rx_out_write (never blocks past a stop) */
    rx_out_private(1);
    rx_out_private(2);
    app.period = app.cfg.period;
    app.header_est = -1;
    app.live.mode = app.cfg.link; /* with auto: nothing heard yet */
    rate_check(&app, app.cfg.period, app.cfg.link);
    app.fd = rx_serial_open(app.cfg.port, app.cfg.baud, msg, sizeof msg);
    if (app.fd < 0) {
        int e = errno;
        rx_log(&app.stop, "%s", msg);
        return rx_open_error_code(e);
    }
    if ((rc = rx_gnss_open(&app.gnss, &app.cfg.gnss, &app.stop, app.cfg.reopen_delay, msg, sizeof msg))
        != 0) {
        rx_log(&app.stop, "%s", msg);
        return rc;
    }
    g_stop = &app.stop;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &sa, NULL); /* a closed stdout is reported by write (EPIPE) */

    rx_log(&app.stop, "%s at %ld baud 8N1, block %u bytes, method %s, period %g s%s", app.cfg.port,
           app.cfg.baud, app.cfg.block_size, rx_method_name(app.cfg.method), app.cfg.period,
           app.cfg.period_set ? "" : " until a BOOT report announces it");
    gnss_banner(&app);
    if (pthread_create(&att_thr, NULL, attitude_thread, &app) != 0
        || pthread_create(&rx_thr, NULL, receiver_thread, &app) != 0 || rx_gnss_start(&app.gnss) != 0) {
        rx_log(&app.stop, "cannot start threads");
        return RX_EXIT_INTERNAL;
    }
    pthread_join(rx_thr, NULL);  /* ends at a stop request: at most one hold slice later */
    rx_queue_close(&app.queue);  /* the attitude thread handles what is queued (acknowledged) */
    pthread_join(att_thr, NULL); /* within the grace time if stdout blocks */
    rx_gnss_end(&app.gnss);      /* its thread saw the stop request too */
    if (app.cfg.format == RX_FORMAT_JSONL)
        link_record(&app); /* the final counters */
    if (app.fd >= 0)
        rx_serial_close(app.fd);
    print_statistics(&app);
    rx_queue_destroy(&app.queue);
    if (app.out_error)
        return RX_EXIT_IOERR;
    return app.undelivered || app.lines_lost ? RX_EXIT_TEMPFAIL : RX_EXIT_OK;
}
