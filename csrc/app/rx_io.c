/* attitude-rx: bounded record queue, stop requests, bounded I/O (stdout,
 * stderr, the port) and termios serial port setup. */
#define _DEFAULT_SOURCE 1 /* cfmakeraw */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include "rx.h"

#ifndef PIPE_BUF
#define PIPE_BUF 512 /* POSIX minimum */
#endif

/* ---- time ---- */

static void now_mono(struct timespec *t)
{
    clock_gettime(CLOCK_MONOTONIC, t);
}

/* ms from now until t (0 if past), at most INT_MAX */
static int ms_until(const struct timespec *t)
{
    struct timespec n;
    double ms;
    now_mono(&n);
    ms = (double)(t->tv_sec - n.tv_sec) * 1e3 + (double)(t->tv_nsec - n.tv_nsec) / 1e6;
    if (ms <= 0)
        return 0;
    return ms >= (double)INT_MAX ? INT_MAX : (int)ms + 1;
}

/* ---- queue ---- */

int rx_queue_init(rx_queue *q, unsigned cap)
{
    pthread_condattr_t ca;
    if (cap == 0 || cap > RX_QUEUE_MAX)
        return -1;
    memset(q, 0, sizeof *q);
    q->cap = cap;
    if (pthread_mutex_init(&q->lock, NULL) != 0)
        return -1;
    if (pthread_cond_init(&q->nonempty, NULL) != 0)
        goto fail_lock;
    if (pthread_condattr_init(&ca) != 0)
        goto fail_nonempty;
    if (pthread_condattr_setclock(&ca, CLOCK_MONOTONIC) != 0 || pthread_cond_init(&q->notfull, &ca) != 0) {
        pthread_condattr_destroy(&ca);
        goto fail_nonempty;
    }
    pthread_condattr_destroy(&ca);
    return 0;
fail_nonempty:
    pthread_cond_destroy(&q->nonempty);
fail_lock:
    pthread_mutex_destroy(&q->lock);
    return -1;
}

void rx_queue_destroy(rx_queue *q)
{
    pthread_cond_destroy(&q->notfull);
    pthread_cond_destroy(&q->nonempty);
    pthread_mutex_destroy(&q->lock);
}

/* Room for all n items (caller holds the lock)? */
static int fits(const rx_queue *q, const rx_item *items, unsigned n)
{
    unsigned i, samples = 0;
    for (i = 0; i < n; i++)
        if (items[i].blk.kind == ATT_BLOCK_SAMPLE)
            samples++;
    /* samples may fill up to cap; reports the reserve beyond it */
    return q->count + samples <= q->cap && q->count + n <= q->cap + (unsigned)RX_REPORT_RESERVE;
}

unsigned rx_queue_room(rx_queue *q)
{
    unsigned room;
    pthread_mutex_lock(&q->lock);
    room = q->count < q->cap ? q->cap - q->count : 0u;
    pthread_mutex_unlock(&q->lock);
    return room;
}

int rx_queue_push_all(rx_queue *q, const rx_item *items, unsigned n, const struct timespec *deadline)
{
    const unsigned size = sizeof q->buf / sizeof q->buf[0];
    unsigned i;
    int rc = 0;
    pthread_mutex_lock(&q->lock);
    while (!fits(q, items, n)) {
        if (pthread_cond_timedwait(&q->notfull, &q->lock, deadline) == ETIMEDOUT && !fits(q, items, n)) {
            rc = 1;
            break;
        }
    }
    if (rc == 0) {
        for (i = 0; i < n; i++) {
            q->buf[(q->head + q->count) % size] = items[i];
            q->count++;
            q->pushed++;
        }
        if (q->count > q->high_water)
            q->high_water = q->count;
        pthread_cond_signal(&q->nonempty);
    }
    pthread_mutex_unlock(&q->lock);
    return rc;
}

int rx_queue_pop(rx_queue *q, rx_item *it)
{
    int closed = 0;
    const unsigned size = sizeof q->buf / sizeof q->buf[0];
    pthread_mutex_lock(&q->lock);
    while (q->count == 0 && !q->closed)
        pthread_cond_wait(&q->nonempty, &q->lock);
    if (q->count > 0) {
        *it = q->buf[q->head];
        q->head = (q->head + 1) % size;
        q->count--;
        q->popped++;
        pthread_cond_signal(&q->notfull);
    } else {
        closed = 1;
    }
    pthread_mutex_unlock(&q->lock);
    return closed;
}

void rx_queue_close(rx_queue *q)
{
    pthread_mutex_lock(&q->lock);
    q->closed = 1;
    pthread_cond_broadcast(&q->nonempty);
    pthread_mutex_unlock(&q->lock);
}

void rx_queue_count_failed(rx_queue *q)
{
    pthread_mutex_lock(&q->lock);
    q->failed++;
    pthread_mutex_unlock(&q->lock);
}

unsigned long rx_queue_failed(rx_queue *q)
{
    unsigned long f;
    pthread_mutex_lock(&q->lock);
    f = q->failed;
    pthread_mutex_unlock(&q->lock);
    return f;
}

/* ---- stop requests ---- */

int rx_stop_init(rx_stop *s)
{
    int p[2], fl;
    memset(s, 0, sizeof *s);
    if (pipe(p) != 0)
        return -1;
    s->wake_rd = p[0];
    s->wake_wr = p[1];
    fl = fcntl(s->wake_wr, F_GETFL);
    if (fl < 0 || fcntl(s->wake_wr, F_SETFL, fl | O_NONBLOCK) != 0) /* a full pipe never blocks a handler */
        return -1;
    return pthread_mutex_init(&s->lock, NULL) == 0 ? 0 : -1;
}

void rx_stop_request(rx_stop *s)
{
    char c = 's';
    ssize_t r = write(s->wake_wr, &c, 1); /* async-signal-safe */
    (void)r;
}

/* The request was seen: start the grace time (once). */
static void stop_seen(rx_stop *s)
{
    pthread_mutex_lock(&s->lock);
    if (!s->stopping) {
        s->stopping = 1;
        now_mono(&s->deadline);
        s->deadline.tv_sec += RX_STOP_GRACE_MS / 1000;
        s->deadline.tv_nsec += (long)(RX_STOP_GRACE_MS % 1000) * 1000000L;
        if (s->deadline.tv_nsec >= 1000000000L) {
            s->deadline.tv_sec++;
            s->deadline.tv_nsec -= 1000000000L;
        }
    }
    pthread_mutex_unlock(&s->lock);
}

static int stopping(rx_stop *s, struct timespec *deadline)
{
    int st;
    pthread_mutex_lock(&s->lock);
    st = s->stopping;
    if (deadline != NULL)
        *deadline = s->deadline;
    pthread_mutex_unlock(&s->lock);
    return st;
}

int rx_stop_wait(rx_stop *s, double seconds)
{
    struct pollfd p;
    int ms = seconds <= 0 ? 0 : (int)(seconds * 1000.0 + 0.5);
    if (stopping(s, NULL))
        return 1;
    p.fd = s->wake_rd;
    p.events = POLLIN;
    p.revents = 0;
    if (poll(&p, 1, ms) > 0 && (p.revents & POLLIN)) {
        stop_seen(s);
        return 1;
    }
    return 0; /* timeout, or EINTR: a signal's byte is seen by the next call */
}

int rx_stop_check(rx_stop *s)
{
    return rx_stop_wait(s, 0);
}

/* ---- bounded output ---- */

void rx_out_private(int fd)
{
    struct stat st;
    char path[32];
    int fl, nfd;
    if (fstat(fd, &st) != 0 || !(S_ISFIFO(st.st_mode) || S_ISCHR(st.st_mode)))
        return;
    fl = fcntl(fd, F_GETFL);
    if (fl < 0 || (fl & O_NONBLOCK))
        return;
    snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    nfd = open(path, O_WRONLY | O_NOCTTY | O_NONBLOCK | (fl & O_APPEND));
    if (nfd < 0)
        return; /* no /proc, or a FIFO without reader: keep the fd (poll before each write) */
    if (nfd != fd) {
        dup2(nfd, fd);
        close(nfd);
    }
}

int rx_out_write(rx_stop *s, int fd, const char *p, size_t n)
{
    const int fl = fcntl(fd, F_GETFL);
    int ready = fl >= 0 && (fl & O_NONBLOCK); /* non-blocking: try the write first */
    while (n > 0) {
        struct pollfd pf[2];
        struct timespec dl;
        int nf = 2, timeout = -1, r;
        ssize_t w;
        if (ready) {
            /* a blocking fd gets at most PIPE_BUF bytes after POLLOUT: a pipe then never blocks */
            w = write(fd, p, n < (size_t)PIPE_BUF || (fl & O_NONBLOCK) ? n : (size_t)PIPE_BUF);
            if (w >= 0) {
                p += w;
                n -= (size_t)w;
                ready = fl >= 0 && (fl & O_NONBLOCK);
                continue;
            }
            if (errno != EINTR && errno != EAGAIN)
                return -1;
        }
        if (stopping(s, &dl)) { /* no more waiting for the stop pipe: only for the grace time */
            nf = 1;
            timeout = ms_until(&dl);
        }
        pf[0].fd = fd;
        pf[0].events = POLLOUT;
        pf[1].fd = s->wake_rd;
        pf[1].events = POLLIN;
        pf[0].revents = pf[1].revents = 0;
        r = poll(pf, (nfds_t)nf, timeout);
        if (r < 0) {
            if (errno == EINTR)
                continue; /* the handler's byte wakes the next poll */
            return -1;
        }
        if (nf == 2 && (pf[1].revents & POLLIN)) {
            stop_seen(s);
            continue;
        }
        if (r == 0)
            return 1; /* grace time over, fd still blocked */
        ready = 1;    /* POLLOUT, or POLLERR/POLLHUP: the write says which error */
    }
    return 0;
}

void rx_log(rx_stop *s, const char *fmt, ...)
{
    char line[RX_LINE_MAX];
    va_list ap;
    int k = snprintf(line, sizeof line, "attitude-rx: ");
    size_t len;
    va_start(ap, fmt);
    vsnprintf(line + k, sizeof line - (size_t)k - 1, fmt, ap);
    va_end(ap);
    len = strlen(line);
    line[len++] = '\n';
    (void)rx_out_write(s, 2, line, len); /* a log that cannot be written is lost, never waited for */
}

int rx_port_write(rx_stop *s, int fd, const uint8_t *p, size_t n)
{
    while (n > 0) {
        struct pollfd pf[2];
        ssize_t w = write(fd, p, n);
        if (w > 0) {
            p += w;
            n -= (size_t)w;
            continue;
        }
        if (w < 0 && errno != EAGAIN && errno != EINTR)
            return -1;
        /* the line does not take the byte now (peer not reading, flow stopped): wait */
        pf[0].fd = fd;
        pf[0].events = POLLOUT;
        pf[1].fd = s->wake_rd;
        pf[1].events = POLLIN;
        pf[0].revents = pf[1].revents = 0;
        if (poll(pf, 2, -1) < 0 && errno != EINTR)
            return -1;
        if (pf[1].revents & POLLIN) {
            stop_seen(s);
            return 1;
        }
    }
    return 0;
}

/* ---- serial port ---- */

static const struct {
    long rate;
    speed_t code;
} bauds[] = {
    { 1200, B1200 },   { 2400, B2400 },   { 4800, B4800 },     { 9600, B9600 },     { 19200, B19200 },
    { 38400, B38400 }, { 57600, B57600 }, { 115200, B115200 }, { 230400, B230400 },
};

static int baud_code(long baud, speed_t *code)
{
    size_t i;
    for (i = 0; i < sizeof bauds / sizeof bauds[0]; i++)
        if (bauds[i].rate == baud) {
            *code = bauds[i].code;
            return 0;
        }
    return -1;
}

int rx_serial_baud_ok(long baud)
{
    speed_t c;
    return baud_code(baud, &c) == 0;
}

int rx_open_error_code(int err)
{
    if (err == ENOENT || err == ENODEV || err == ENXIO || err == ENOTDIR)
        return RX_EXIT_NOPORT;
    if (err == EACCES || err == EPERM)
        return RX_EXIT_NOPERM;
    return RX_EXIT_IOERR;
}

int rx_serial_open(const char *path, long baud, char *msg, size_t len)
{
    struct termios tio;
    speed_t code;
    int fd, e;
    if (baud_code(baud, &code) != 0) {
        snprintf(msg, len, "unsupported baud rate %ld", baud);
        errno = EINVAL;
        return -1;
    }
    /* O_NONBLOCK: do not wait for carrier detect while opening, and never
     * block in read or write afterwards (both wait in poll()) */
    fd = open(path, O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (fd < 0) {
        e = errno;
        snprintf(msg, len, "cannot open port %s: %s", path, strerror(e));
        errno = e;
        return -1;
    }
    if (tcgetattr(fd, &tio) != 0) {
        e = errno;
        snprintf(msg, len, "port %s is not a serial port (tcgetattr: %s)", path, strerror(e));
        close(fd);
        errno = e;
        return -1;
    }
    /* 8N1 raw, receiver on, modem control lines ignored, no flow control */
    cfmakeraw(&tio);
    tio.c_cflag &= ~(tcflag_t)(CSIZE | PARENB | CSTOPB);
#ifdef CRTSCTS
    tio.c_cflag &= ~(tcflag_t)CRTSCTS;
#endif
    tio.c_cflag |= CS8 | CREAD | CLOCAL;
    tio.c_iflag &= ~(tcflag_t)(IXON | IXOFF | IXANY);
    tio.c_cc[VMIN] = 1;
    tio.c_cc[VTIME] = 0;
    if (cfsetispeed(&tio, code) != 0 || cfsetospeed(&tio, code) != 0 || tcsetattr(fd, TCSANOW, &tio) != 0) {
        e = errno;
        snprintf(msg, len, "cannot configure port %s: %s", path, strerror(e));
        close(fd);
        errno = e;
        return -1;
    }
    tcflush(fd, TCIFLUSH);
    return fd;
}

void rx_serial_close(int fd)
{
    int left = 0, before = -1, still = 0;
    /* wait while the output queue shrinks; what stops moving for RX_DRAIN_STUCK_MS is dropped */
    while (ioctl(fd, TIOCOUTQ, &left) == 0 && left > 0 && still < RX_DRAIN_STUCK_MS) {
        still = left == before ? still + 10 : 0;
        before = left;
        (void)poll(NULL, 0, 10);
    }
    if (left > 0)
        tcflush(fd, TCOFLUSH);
    close(fd);
}
