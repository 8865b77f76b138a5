/*
 * AD7927 frame-transfer HAL on Linux spidev. See
 * attitude/ad7927_spidev.h and docs/ad7927.md ("The spidev HAL").
 */
#define _POSIX_C_SOURCE 200809L

#include "attitude/ad7927_spidev.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

static int os_ioctl(void *ctx, int fd, unsigned long request, void *arg)
{
    (void)ctx;
    return ioctl(fd, request, arg);
}

static void os_sleep_ns(void *ctx, uint32_t ns)
{
    struct timespec ts, rem;
    (void)ctx;
    ts.tv_sec = (time_t)(ns / 1000000000u);
    ts.tv_nsec = (long)(ns % 1000000000u);
    while (nanosleep(&ts, &rem) != 0 && errno == EINTR) {
        ts = rem;
    }
}

void ad7927_spidev_os_default(ad7927_spidev_os *os)
{
    if (os != 0) {
        os->ctx = 0;
        os->ioctl = os_ioctl;
        os->sleep_ns = os_sleep_ns;
    }
}

/* One setup ioctl; records errno on failure. */
static int setup(ad7927_spidev *s, unsigned long request, void *arg)
{
    if (s->os.ioctl(s->os.ctx, s->fd, request, arg) < 0) {
        s->last_errno = errno ? errno : EIO;
        return AD7927_E_TRANSFER;
    }
    return ATT_OK;
}

int ad7927_spidev_attach(ad7927_spidev *s, int fd, uint32_t speed_hz, const ad7927_spidev_os *os,
                         ad7927_hal *hal)
{
    uint8_t mode = SPI_MODE_2, bits = 8u;
    uint32_t speed = speed_hz;
    int st;
    if (s == 0 || hal == 0 || (os != 0 && (os->ioctl == 0 || os->sleep_ns == 0))) {
        return ATT_E_NULL;
    }
    if (speed_hz < AD7927_SPIDEV_HZ_MIN || speed_hz > AD7927_SPIDEV_HZ_MAX || fd < 0) {
        return ATT_E_ARG;
    }
    memset(s, 0, sizeof *s);
    s->fd = fd;
    s->speed_hz = speed_hz;
    if (os != 0) {
        s->os = *os;
    } else {
        ad7927_spidev_os_default(&s->os);
    }
    st = setup(s, SPI_IOC_WR_MODE, &mode);
    if (st == ATT_OK) {
        st = setup(s, SPI_IOC_WR_BITS_PER_WORD, &bits);
    }
    if (st == ATT_OK) {
        st = setup(s, SPI_IOC_WR_MAX_SPEED_HZ, &speed);
    }
    if (st != ATT_OK) {
        return st;
    }
    hal->ctx = s;
    hal->transfer = ad7927_spidev_transfer;
    return ATT_OK;
}

int ad7927_spidev_open(ad7927_spidev *s, const char *path, uint32_t speed_hz, ad7927_hal *hal)
{
    int fd, st;
    if (s == 0 || path == 0 || hal == 0) {
        return ATT_E_NULL;
    }
    if (speed_hz < AD7927_SPIDEV_HZ_MIN || speed_hz > AD7927_SPIDEV_HZ_MAX) {
        return ATT_E_ARG;
    }
    fd = open(path, O_RDWR);
    if (fd < 0) {
        memset(s, 0, sizeof *s);
        s->fd = -1;
        s->last_errno = errno;
        return AD7927_E_TRANSFER;
    }
    st = ad7927_spidev_attach(s, fd, speed_hz, 0, hal);
    if (st != ATT_OK) {
        int e = s->last_errno;
        (void)close(fd);
        s->fd = -1;
        s->last_errno = e;
        return st;
    }
    s->owns_fd = 1;
    return ATT_OK;
}

int ad7927_spidev_close(ad7927_spidev *s)
{
    if (s == 0) {
        return ATT_E_NULL;
    }
    if (s->owns_fd && s->fd >= 0 && close(s->fd) != 0) {
        s->last_errno = errno;
        s->fd = -1;
        return AD7927_E_TRANSFER;
    }
    s->fd = -1;
    s->owns_fd = 0;
    return ATT_OK;
}

int ad7927_spidev_transfer(void *ctx, const uint16_t *tx, uint16_t *rx, uint8_t n, uint32_t hold_ns)
{
    static const struct spi_ioc_transfer zero; /* unused fields must be zero */
    ad7927_spidev *s = (ad7927_spidev *)ctx;
    uint8_t i;
    int r;
    if (s == 0 || tx == 0 || rx == 0 || n == 0u || n > AD7927_MAX_FRAMES) {
        return -1;
    }
    for (i = 0u; i < n; i++) {
        s->xfer[i] = zero;
        s->tx[2u * i] = (uint8_t)(tx[i] >> 8); /* MSB first on the wire */
        s->tx[2u * i + 1u] = (uint8_t)(tx[i] & 0xFFu);
        s->xfer[i].tx_buf = (uint64_t)(uintptr_t)&s->tx[2u * i];
        s->xfer[i].rx_buf = (uint64_t)(uintptr_t)&s->rx[2u * i];
        s->xfer[i].len = 2u;
        s->xfer[i].speed_hz = s->speed_hz;
        s->xfer[i].bits_per_word = 8u;
        s->xfer[i].cs_change = (uint8_t)(i + 1u < n); /* CS high between frames, not after the last */
    }
    r = s->os.ioctl(s->os.ctx, s->fd, SPI_IOC_MESSAGE(n), s->xfer);
    if (r != 2 * (int)n) { /* -1 and errno, or a short transfer (EIO) */
        s->last_errno = (r < 0 && errno != 0) ? errno : EIO;
        return -1;
    }
    for (i = 0u; i < n; i++) {
        rx[i] = (uint16_t)(((unsigned)s->rx[2u * i] << 8) | s->rx[2u * i + 1u]);
    }
    if (hold_ns > AD7927_T_QUIET_NS) {
        s->os.sleep_ns(s->os.ctx, hold_ns); /* CS is high once the message is done */
    }
    s->last_errno = 0;
    return 0;
}
