/*
 * The spidev HAL against the C twin of the AD7927 model, through its
 * operating-system seam: an injected ioctl decodes every SPI_IOC_* request
 * the HAL makes (checking it against the spidev ABI and the AD7927's needs)
 * and runs each spi_ioc_transfer as one frame of the model; an injected
 * sleep advances the model's clock. No device needed. Expected bytes come
 * from the datasheet's bit tables.
 */
#include <errno.h>
#include <string.h>

#include "att_test.h"
#include "attitude/ad7927.h"
#include "attitude/ad7927_spidev.h"
#include "ad7927_model.h"

#define FAKE_FD 42
#define MAX_LOG 64

/* What the fake kernel saw. */
typedef struct {
    ad7927m *model;
    uint8_t mode, bits;
    uint32_t max_speed;
    int setups, messages, bad; /* bad: ABI checks that failed */
    int fail_request;          /* 1 + index of the ioctl call to fail with EIO; 0: none */
    int short_by;              /* bytes to report short on a message */
    int calls;
    uint8_t tx[MAX_LOG][2], rx[MAX_LOG][2];
    uint8_t cs_change[MAX_LOG];
    int frames; /* entries logged */
    int frames_per_message[MAX_LOG];
    uint64_t slept_ns;
} fake_kernel;

static int fake_ioctl(void *ctx, int fd, unsigned long request, void *arg)
{
    fake_kernel *k = (fake_kernel *)ctx;
    k->calls++;
    if (fd != FAKE_FD) {
        k->bad++;
    }
    if (k->fail_request == k->calls) {
        errno = EIO;
        return -1;
    }
    if (request == SPI_IOC_WR_MODE) {
        k->mode = *(uint8_t *)arg;
        k->setups++;
        return 0;
    }
    if (request == SPI_IOC_WR_BITS_PER_WORD) {
        k->bits = *(uint8_t *)arg;
        k->setups++;
        return 0;
    }
    if (request == SPI_IOC_WR_MAX_SPEED_HZ) {
        k->max_speed = *(uint32_t *)arg;
        k->setups++;
        return 0;
    }
    if (_IOC_TYPE(request) == SPI_IOC_MAGIC && _IOC_NR(request) == 0 && _IOC_DIR(request) == _IOC_WRITE) {
        /* SPI_IOC_MESSAGE(n): the size field says how many transfers */
        const struct spi_ioc_transfer *t = (const struct spi_ioc_transfer *)arg;
        unsigned n = _IOC_SIZE(request) / (unsigned)sizeof(struct spi_ioc_transfer), i;
        if (k->messages < MAX_LOG) {
            k->frames_per_message[k->messages] = (int)n;
        }
        k->messages++;
        for (i = 0; i < n; i++) {
            const uint8_t *txb = (const uint8_t *)(uintptr_t)t[i].tx_buf;
            uint8_t *rxb = (uint8_t *)(uintptr_t)t[i].rx_buf;
            uint16_t w = (uint16_t)((txb[0] << 8) | txb[1]), r = 0;
            /* one 16-clock frame: 2 bytes, 8 bits per word, the configured
             * speed, no delay, CS toggled between frames only */
            if (t[i].len != 2u || t[i].bits_per_word != 8u || t[i].speed_hz != k->max_speed
                || t[i].delay_usecs != 0u || t[i].cs_change != (i + 1u < n) || t[i].pad != 0u) {
                k->bad++;
            }
            /* the model at the bus's SCLK; CS high t_QUIET after each frame */
            k->model->sclk_period_ns = (int32_t)((1000000000u + t[i].speed_hz - 1u) / t[i].speed_hz);
            if (ad7927m_transfer(k->model, &w, &r, 1u, AD7927_T_QUIET_NS) != 0) {
                k->bad++;
            }
            rxb[0] = (uint8_t)(r >> 8);
            rxb[1] = (uint8_t)(r & 0xFFu);
            if (k->frames < MAX_LOG) {
                memcpy(k->tx[k->frames], txb, 2);
                memcpy(k->rx[k->frames], rxb, 2);
                k->cs_change[k->frames] = t[i].cs_change;
            }
            k->frames++;
        }
        return (int)(2u * n) - k->short_by;
    }
    k->bad++;
    errno = ENOTTY;
    return -1;
}

static void fake_sleep(void *ctx, uint32_t ns)
{
    fake_kernel *k = (fake_kernel *)ctx;
    k->slept_ns += ns;
    k->model->t += ns;
}

static ad7927m model;
static fake_kernel kern;
static ad7927_spidev bus;
static ad7927_hal hal;
static ad7927 adc;

static void setup(void)
{
    ad7927_spidev_os os;
    double v[8];
    int i;
    memset(&kern, 0, sizeof kern);
    CHECK_EQ_INT(ad7927m_init(&model, 2.5, AD7927M_POWERUP_CONTROL, 1), ATT_OK);
    for (i = 0; i < 8; i++) {
        v[i] = 0.3 + 0.6 * i;
    }
    CHECK_EQ_INT(ad7927m_set_inputs(&model, v, 8), ATT_OK);
    kern.model = &model;
    os.ctx = &kern;
    os.ioctl = fake_ioctl;
    os.sleep_ns = fake_sleep;
    CHECK_EQ_INT(ad7927_spidev_attach(&bus, FAKE_FD, 9260000u, &os, &hal), ATT_OK);
    CHECK_EQ_INT(ad7927_init(&adc, &hal, 0), ATT_OK);
}

/* Control write from the datasheet (Table 5), straight binary, 0..2*REFIN,
 * normal power: the 16-bit frame as two bytes, MSB first. */
static void expect_frame(int idx, unsigned seq, unsigned add, unsigned shadow)
{
    unsigned w = ((1u << 11) | (seq << 10) | (add << 6) | (3u << 4) | (shadow << 3) | 1u) << 4;
    CHECK_EQ_INT(kern.tx[idx][0], w >> 8);
    CHECK_EQ_INT(kern.tx[idx][1], w & 0xFFu);
}

static void test_setup_and_power_up(void)
{
    setup();
    CHECK_EQ_INT(kern.setups, 3);
    CHECK_EQ_INT(kern.mode, SPI_MODE_2); /* CPOL = 1, CPHA = 0 */
    CHECK_EQ_INT(kern.bits, 8);
    CHECK_EQ_INT(kern.max_speed, 9260000);
    CHECK(hal.ctx == &bus && hal.transfer == ad7927_spidev_transfer);
    CHECK_EQ_INT(ad7927_power_up(&adc), ATT_OK);
    /* three messages of one frame: FF FF, FF FF, then the first write */
    CHECK_EQ_INT(kern.messages, 3);
    CHECK_EQ_INT(kern.tx[0][0], 0xFF);
    CHECK_EQ_INT(kern.tx[0][1], 0xFF);
    CHECK_EQ_INT(kern.tx[1][0], 0xFF);
    expect_frame(2, 0, 0, 0); /* 83 10 */
    CHECK_EQ_INT(kern.tx[2][0], 0x83);
    CHECK_EQ_INT(kern.tx[2][1], 0x10);
    /* t_POWER-UP after each DIN-high frame: two sleeps of 1 us */
    CHECK_EQ_INT(kern.slept_ns, 2000);
    /* frame 3's answer: leading 0, ADD 000, the VIN0 code in 0..REFIN */
    CHECK_EQ_INT((kern.rx[2][0] << 8) | kern.rx[2][1], ad7927m_quantize(0.3, 2.5, 0));
    CHECK_EQ_INT(kern.bad, 0);
    CHECK_EQ_INT(model.violation, AD7927M_V_NONE);
}

static void test_scan_one_message(void)
{
    static const uint8_t ch[7] = { 0, 1, 2, 3, 4, 5, 6 };
    int16_t codes[7];
    int i, f0;
    setup();
    CHECK_EQ_INT(ad7927_power_up(&adc), ATT_OK);
    f0 = kern.frames;
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 7, codes, 0), ATT_OK);
    CHECK_EQ_INT(kern.messages, 4);
    CHECK_EQ_INT(kern.frames_per_message[3], 7); /* the whole scan in one SPI_IOC_MESSAGE(7) */
    for (i = 0; i < 7; i++) {
        CHECK_EQ_INT(codes[i], ad7927m_quantize(0.3 + 0.6 * i, 2.5, 1));
        expect_frame(f0 + i, 0, i < 6 ? (unsigned)i + 1u : 0u, 0);
        CHECK_EQ_INT(kern.cs_change[f0 + i], i < 6);
        /* the answer: 0, ADD2..0 = i, then the 12 data bits, big-endian */
        CHECK_EQ_INT(kern.rx[f0 + i][0] >> 4, i);
        CHECK_EQ_INT(((kern.rx[f0 + i][0] & 0x0F) << 8) | kern.rx[f0 + i][1], codes[i]);
    }
    /* the sequencer through spidev: one write, then WRITE = 0 frames (00 00) */
    f0 = kern.frames;
    CHECK_EQ_INT(ad7927_seq_start(&adc, 6), ATT_OK);
    expect_frame(f0, 1, 6, 1); /* DB 90 */
    CHECK_EQ_INT(ad7927_seq_read(&adc, codes, 0, 7), ATT_OK);
    for (i = 0; i < 7; i++) {
        CHECK_EQ_INT(kern.tx[f0 + 1 + i][0], 0);
        CHECK_EQ_INT(kern.tx[f0 + 1 + i][1], 0);
        CHECK_EQ_INT(codes[i], ad7927m_quantize(0.3 + 0.6 * i, 2.5, 1));
    }
    CHECK_EQ_INT(kern.bad, 0);
    CHECK_EQ_INT(model.violation, AD7927M_V_NONE);
}

static void test_faults(void)
{
    static const uint8_t ch[2] = { 2, 3 };
    int16_t codes[2];
    ad7927_spidev_os os;
    /* a failing message: E_TRANSFER, errno kept */
    setup();
    CHECK_EQ_INT(ad7927_power_up(&adc), ATT_OK);
    kern.fail_request = kern.calls + 1;
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 2, codes, 2), AD7927_E_TRANSFER);
    CHECK_EQ_INT(bus.last_errno, EIO);
    CHECK_EQ_INT(adc.pending, AD7927_NO_CHANNEL);
    /* and the next scan works again */
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 2, codes, 2), ATT_OK);
    CHECK_EQ_INT(codes[1], ad7927m_quantize(2.1, 2.5, 1));
    /* a short transfer */
    kern.short_by = 1;
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 2, codes, 2), AD7927_E_TRANSFER);
    CHECK_EQ_INT(bus.last_errno, EIO);
    kern.short_by = 0;
    /* a wrong channel address still comes out as the driver's check */
    model.address_xor = 1;
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 2, codes, 2), AD7927_E_CHANNEL);
    /* setup failures: the mode ioctl fails */
    memset(&kern, 0, sizeof kern);
    kern.model = &model;
    kern.fail_request = 1;
    os.ctx = &kern;
    os.ioctl = fake_ioctl;
    os.sleep_ns = fake_sleep;
    CHECK_EQ_INT(ad7927_spidev_attach(&bus, FAKE_FD, 9260000u, &os, &hal), AD7927_E_TRANSFER);
    CHECK_EQ_INT(bus.last_errno, EIO);
    /* arguments */
    CHECK_EQ_INT(ad7927_spidev_attach(&bus, FAKE_FD, 30000000u, &os, &hal), ATT_E_ARG);
    CHECK_EQ_INT(ad7927_spidev_attach(&bus, FAKE_FD, 5000u, &os, &hal), ATT_E_ARG);
    CHECK_EQ_INT(ad7927_spidev_attach(0, FAKE_FD, 9260000u, &os, &hal), ATT_E_NULL);
    CHECK_EQ_INT(ad7927_spidev_transfer(&bus, 0, 0, 1, 0), -1);
    /* the real open(2) on a path that does not exist */
    CHECK_EQ_INT(ad7927_spidev_open(&bus, "/nonexistent/spidev9.9", 9260000u, &hal), AD7927_E_TRANSFER);
    CHECK_EQ_INT(bus.last_errno, ENOENT);
    CHECK_EQ_INT(bus.fd, -1);
    CHECK_EQ_INT(ad7927_spidev_close(&bus), ATT_OK);
}

int main(void)
{
    test_setup_and_power_up();
    test_scan_one_message();
    test_faults();
    return ATT_TEST_REPORT();
}
