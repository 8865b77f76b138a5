/*
 * Instruction-count harness for bench/ad7927.py: N 7-channel reads of the
 * AD7927 driver through one HAL, against a minimal fake device (a shift
 * register that answers each frame with the channel the last write selected,
 * so every driver check passes). Run under qemu-arm with
 * `-singlestep -d nochain,exec` (toolchain/qemu_count.py) with two values of
 * N: the difference divided by the difference in N is the cost of one read
 * (start-up cancels out).
 *
 *   ad7927_armv4t HAL MODE N
 *     HAL  = pins   (ad7927_pins_transfer over pin callbacks)
 *          | frames (a frame-transfer callback, as an SPI controller driver)
 *          | spidev (the Linux spidev HAL over a fake ioctl; Linux builds only)
 *     MODE = scan   (ad7927_scan of VIN0..VIN6, next = VIN0: 7 frames)
 *          | seq    (ad7927_seq_read of the sequence VIN0..VIN6: 7 frames)
 *          | fake   (the fake device alone, called as the HAL would call it
 *                    for one scan: its share of the other figures)
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "attitude/ad7927.h"
#ifdef __linux__
#include "attitude/ad7927_spidev.h"
#endif

/* The fake AD7927: answers (channel << 12) | 0x800; follows plain writes
 * and the consecutive sequence (all this bench uses). */
typedef struct {
    uint16_t out, din_word;
    uint8_t next, last, seq, din;
} fake;

static void fake_end(fake *f, uint16_t din)
{
    if (din & 0x8000u) {
        unsigned cw = din >> 4, add = (cw >> 6) & 7u;
        if ((cw & 0x400u) && (cw & 0x8u)) {
            f->seq = 1u;
            f->last = (uint8_t)add;
            f->next = 0u;
        } else if (!(cw & 0x400u)) {
            f->seq = 0u;
            f->next = (uint8_t)add;
        }
    } else if (f->seq) {
        f->next = (uint8_t)(f->next == f->last ? 0u : f->next + 1u);
    }
}

static uint16_t fake_frame(fake *f, uint16_t din)
{
    uint16_t out = (uint16_t)(((unsigned)f->next << 12) | 0x800u);
    fake_end(f, din);
    return out;
}

/* pins */
static void p_cs(void *c, int v)
{
    fake *f = (fake *)c;
    if (!v) {
        f->out = (uint16_t)(((unsigned)f->next << 12) | 0x800u);
        f->din_word = 0u;
    } else {
        fake_end(f, f->din_word);
    }
}
static void p_sclk(void *c, int v)
{
    fake *f = (fake *)c;
    if (!v) {
        f->din_word = (uint16_t)(((unsigned)f->din_word << 1) | f->din);
        f->out = (uint16_t)(f->out << 1);
    }
}
static void p_din(void *c, int v)
{
    ((fake *)c)->din = (uint8_t)(v != 0);
}
static int p_dout(void *c)
{
    return (((fake *)c)->out >> 15) & 1;
}
static void p_delay(void *c, uint32_t ns)
{
    (void)c;
    (void)ns;
}

/* frames */
static int f_transfer(void *c, const uint16_t *tx, uint16_t *rx, uint8_t n, uint32_t hold_ns)
{
    uint8_t i;
    (void)hold_ns;
    for (i = 0u; i < n; i++) {
        rx[i] = fake_frame((fake *)c, tx[i]);
    }
    return 0;
}

#ifdef __linux__
/* spidev: the kernel side of SPI_IOC_MESSAGE, one fake frame per transfer */
static int s_ioctl(void *c, int fd, unsigned long request, void *arg)
{
    (void)fd;
    if (_IOC_TYPE(request) == SPI_IOC_MAGIC && _IOC_NR(request) == 0) {
        const struct spi_ioc_transfer *t = (const struct spi_ioc_transfer *)arg;
        unsigned n = _IOC_SIZE(request) / (unsigned)sizeof *t, i;
        for (i = 0; i < n; i++) {
            const uint8_t *tb = (const uint8_t *)(uintptr_t)t[i].tx_buf;
            uint8_t *rb = (uint8_t *)(uintptr_t)t[i].rx_buf;
            uint16_t r = fake_frame((fake *)c, (uint16_t)((tb[0] << 8) | tb[1]));
            rb[0] = (uint8_t)(r >> 8);
            rb[1] = (uint8_t)r;
        }
        return (int)(2u * n);
    }
    return 0; /* setup ioctls */
}
static void s_sleep(void *c, uint32_t ns)
{
    (void)c;
    (void)ns;
}
#endif

int main(int argc, char **argv)
{
    static const uint8_t ch[7] = { 0, 1, 2, 3, 4, 5, 6 };
    static fake dev_fake;
    static ad7927_pins pins;
    static ad7927_hal hal;
    static ad7927 adc;
#ifdef __linux__
    static ad7927_spidev bus;
#endif
    int16_t codes[7];
    unsigned long n, i;
    int seq, only_fake, k;
    if (argc != 4) {
        return 2;
    }
    seq = strcmp(argv[2], "seq") == 0;
    only_fake = strcmp(argv[2], "fake") == 0;
    if (!seq && !only_fake && strcmp(argv[2], "scan") != 0) {
        return 2;
    }
    n = strtoul(argv[3], NULL, 10);
    if (strcmp(argv[1], "pins") == 0) {
        pins.ctx = &dev_fake;
        pins.set_cs = p_cs;
        pins.set_sclk = p_sclk;
        pins.set_din = p_din;
        pins.get_dout = p_dout;
        pins.delay_ns = p_delay;
        hal.ctx = &pins;
        hal.transfer = ad7927_pins_transfer;
    } else if (strcmp(argv[1], "frames") == 0) {
        hal.ctx = &dev_fake;
        hal.transfer = f_transfer;
#ifdef __linux__
    } else if (strcmp(argv[1], "spidev") == 0) {
        ad7927_spidev_os os;
        os.ctx = &dev_fake;
        os.ioctl = s_ioctl;
        os.sleep_ns = s_sleep;
        if (ad7927_spidev_attach(&bus, 3, 9260000u, &os, &hal) != ATT_OK) {
            return 3;
        }
#endif
    } else {
        return 2;
    }
    if (only_fake) {
        /* The fake's share of one scan: the 7 frames of a scan delivered to it
         * the way the HAL delivers them, through the same function pointers
         * (read once from volatile storage, so the calls stay indirect and
         * are not inlined), without the driver. */
        const ad7927_pins *volatile pv = &pins;
        const ad7927_pins *pp = pv;
        int (*volatile xv)(void *, const uint16_t *, uint16_t *, uint8_t, uint32_t) = f_transfer;
        int (*xfer)(void *, const uint16_t *, uint16_t *, uint8_t, uint32_t) = xv;
        uint16_t tx[7], rx[7] = { 0, 0, 0, 0, 0, 0, 0 };
        for (k = 0; k < 7; k++) {
            tx[k] = ad7927_din_word((uint16_t)(0x31u | (unsigned)ch[(k + 1) % 7] << 6));
        }
        for (i = 0; i < n; i++) {
            if (hal.transfer == f_transfer) {
                xfer(&dev_fake, tx, rx, 7u, 50u);
            } else if (hal.transfer == ad7927_pins_transfer) {
                for (k = 0; k < 7; k++) { /* the pin calls of one frame */
                    int b;
                    pp->set_cs(pp->ctx, 0);
                    pp->delay_ns(pp->ctx, 35u);
                    for (b = 15; b >= 0; b--) {
                        pp->set_din(pp->ctx, (tx[k] >> b) & 1);
                        pp->delay_ns(pp->ctx, 10u);
                        rx[k] = (uint16_t)((rx[k] << 1) | (uint16_t)pp->get_dout(pp->ctx));
                        pp->set_sclk(pp->ctx, 0);
                        pp->delay_ns(pp->ctx, 40u);
                        pp->set_sclk(pp->ctx, 1);
                        pp->delay_ns(pp->ctx, 20u);
                    }
                    pp->set_cs(pp->ctx, 1);
                    pp->delay_ns(pp->ctx, 50u);
                }
            }
#ifdef __linux__
            else {
                static struct spi_ioc_transfer msg[7];
                static uint8_t tb[14], rb[14];
                int (*volatile kv)(void *, int, unsigned long, void *) = s_ioctl;
                int (*kernel)(void *, int, unsigned long, void *) = kv;
                for (k = 0; k < 7; k++) {
                    tb[2 * k] = (uint8_t)(tx[k] >> 8);
                    tb[2 * k + 1] = (uint8_t)tx[k];
                    msg[k].tx_buf = (uint64_t)(uintptr_t)&tb[2 * k];
                    msg[k].rx_buf = (uint64_t)(uintptr_t)&rb[2 * k];
                }
                kernel(&dev_fake, 3, SPI_IOC_MESSAGE(7), msg);
                rx[0] = (uint16_t)((rb[0] << 8) | rb[1]);
            }
#endif
        }
        printf("%u\n", (unsigned)rx[0]);
        return 0;
    }
    if (ad7927_init(&adc, &hal, 0) != ATT_OK || ad7927_power_up(&adc) != ATT_OK) {
        return 4;
    }
    if (seq ? ad7927_seq_start(&adc, 6) : ad7927_scan(&adc, ch, 7, codes, 0)) {
        return 5;
    }
    for (i = 0; i < n; i++) {
        int st = seq ? ad7927_seq_read(&adc, codes, 0, 7) : ad7927_scan(&adc, ch, 7, codes, 0);
        if (st != ATT_OK) {
            return 6;
        }
    }
    printf("%d\n", codes[6]);
    return 0;
}
