/*
 * ad7927_spidev.h — the AD7927 frame-transfer HAL on Linux spidev
 * (platform code: built by the Linux cross targets, not by the portable
 * library; include with -Icsrc/platform/linux/include).
 *
 * One SPI_IOC_MESSAGE per ad7927_hal.transfer call: one spi_ioc_transfer
 * of 2 bytes (a 16-clock frame, MSB first, big-endian bytes) per frame,
 * cs_change = 1 between them so CS rises between frames, SPI mode 2
 * (CPOL = 1: SCLK idles high; CPHA = 0: data latched on the leading,
 * falling edge), 8 bits per word. A hold longer than t_QUIET after the last
 * frame (t_POWER-UP) is a sleep after the ioctl returns (CS is high by
 * then); within a message the kernel keeps CS high between transfers (and
 * t_QUIET = 50 ns is far shorter than any controller's CS turnaround).
 *
 * The thesis's board (docs/ad7927.md): S3C2440 SPI0, CS on nGCS2, SPPRE = 0
 * -> 9.26 MHz, REFIN 2.5 V, inputs 0-5 V:
 *
 *     ad7927_spidev bus;
 *     ad7927_hal hal;
 *     ad7927 adc;
 *     ad7927_settings s = { 1, 0 };   // RANGE = 0 (0..2*REFIN), straight binary
 *     if (ad7927_spidev_open(&bus, "/dev/spidev0.0", 9260000u, &hal) != ATT_OK) {
 *         perror("spidev0.0");        // bus.last_errno says why
 *     }
 *     ad7927_init(&adc, &hal, &s);
 *     ad7927_power_up(&adc);
 *
 * The operating-system calls go through a seam (ad7927_spidev_os) so that
 * the HAL can be tested without a device: ad7927_spidev_attach() takes an
 * injected ioctl and sleep (tests: csrc/platform/linux/tests/).
 */
#ifndef ATTITUDE_AD7927_SPIDEV_H
#define ATTITUDE_AD7927_SPIDEV_H

#include <linux/spi/spidev.h>

#include "attitude/ad7927.h"

ATT_API_BEGIN

/* SCLK limits of the AD7927 (datasheet f_SCLK). */
enum {
    AD7927_SPIDEV_HZ_MIN = 10000,   /* 10 kHz */
    AD7927_SPIDEV_HZ_MAX = 20000000 /* 20 MHz */
};

/* The operating-system calls of the HAL. ioctl: as ioctl(2) (returns -1 and
 * sets errno on failure); sleep_ns: wait at least ns nanoseconds. */
typedef struct {
    void *ctx;
    int (*ioctl)(void *ctx, int fd, unsigned long request, void *arg);
    void (*sleep_ns)(void *ctx, uint32_t ns);
} ad7927_spidev_os;

/* HAL state: caller-owned (the transfer descriptors live here: no malloc). */
typedef struct {
    int fd;
    int owns_fd; /* 1: opened by ad7927_spidev_open, closed by _close */
    uint32_t speed_hz;
    int last_errno; /* errno of the last failure (0: none) */
    ad7927_spidev_os os;
    struct spi_ioc_transfer xfer[AD7927_MAX_FRAMES];
    uint8_t tx[2 * AD7927_MAX_FRAMES];
    uint8_t rx[2 * AD7927_MAX_FRAMES];
} ad7927_spidev;

/* The real calls: ioctl(2) and nanosleep(2). */
void ad7927_spidev_os_default(ad7927_spidev_os *os);

/* Configure an open spidev descriptor (mode 2, 8 bits per word, speed_hz =
 * AD7927_SPIDEV_HZ_MIN..MAX) through `os` (NULL: the real calls) and fill
 * `hal` (ctx = s, transfer = ad7927_spidev_transfer). ATT_E_NULL, ATT_E_ARG
 * (speed), or AD7927_E_TRANSFER with s->last_errno when an ioctl fails. */
int ad7927_spidev_attach(ad7927_spidev *s, int fd, uint32_t speed_hz, const ad7927_spidev_os *os,
                         ad7927_hal *hal);

/* open(path, O_RDWR) then attach with the real calls. AD7927_E_TRANSFER
 * with s->last_errno when open fails (the descriptor is then -1). */
int ad7927_spidev_open(ad7927_spidev *s, const char *path, uint32_t speed_hz, ad7927_hal *hal);

/* Close a descriptor opened by ad7927_spidev_open (attach: left open). */
int ad7927_spidev_close(ad7927_spidev *s);

/* The ad7927_hal.transfer of this HAL (ctx = the ad7927_spidev). Returns 0,
 * or -1 with s->last_errno (EIO on a short transfer). */
int ad7927_spidev_transfer(void *ctx, const uint16_t *tx, uint16_t *rx, uint8_t n, uint32_t hold_ns);

ATT_API_END

#endif /* ATTITUDE_AD7927_SPIDEV_H */
