/* attitude-rx: bounded record queue and termios serial port setup. */
#define _DEFAULT_SOURCE 1 /* cfmakeraw */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

#include "rx.h"

/* ---- queue ---- */

int rx_queue_init(rx_queue *q, unsigned cap)
{
    if (cap == 0 || cap > RX_QUEUE_MAX)
        return -1;
    memset(q, 0, sizeof *q);
    q->cap = cap;
    if (pthread_mutex_init(&q->lock, NULL) != 0)
        return -1;
    if (pthread_cond_init(&q->nonempty, NULL) != 0) {
        pthread_mutex_destroy(&q->lock);
        return -1;
    }
    return 0;
}

void rx_queue_destroy(rx_queue *q)
{
    pthread_cond_destroy(&q->nonempty);
    pthread_mutex_destroy(&q->lock);
}

int rx_queue_push(rx_queue *q, const rx_item *it)
{
    int full;
    unsigned limit = q->cap + (it->blk.kind == ATT_BLOCK_SAMPLE ? 0u : (unsigned)RX_REPORT_RESERVE);
    const unsigned size = sizeof q->buf / sizeof q->buf[0];
    pthread_mutex_lock(&q->lock);
    full = q->count >= limit;
    if (full) {
        q->overflows++;
    } else {
        q->buf[(q->head + q->count) % size] = *it;
        q->count++;
        q->pushed++;
        if (q->count > q->high_water)
            q->high_water = q->count;
        pthread_cond_signal(&q->nonempty);
    }
    pthread_mutex_unlock(&q->lock);
    return full;
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

int rx_serial_open(const char *path, long baud, char *msg, size_t len)
{
    struct termios tio;
    speed_t code;
    int fd, flags, e;
    if (baud_code(baud, &code) != 0) {
        snprintf(msg, len, "unsupported baud rate %ld", baud);
        errno = EINVAL;
        return -1;
    }
    /* O_NONBLOCK: do not wait for carrier detect while opening */
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
    /* back to blocking I/O: reads are only done after poll() says so */
    flags = fcntl(fd, F_GETFL);
    if (flags >= 0)
        fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    return fd;
}
