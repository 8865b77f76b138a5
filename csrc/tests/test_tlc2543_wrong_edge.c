/*
 * Proof that the device model checks something: the real driver source,
 * compiled with a deliberately broken HAL that samples DATA OUT on the
 * falling edge of I/O CLOCK (the wrong edge: the chip is just shifting the
 * next bit out), is rejected by the C twin of the model with a
 * "DATA OUT read before it is valid" violation, while the same source with
 * the normal host HAL passes (test_tlc2543.c).
 */
#include "att_test.h"

/* The broken variant: every public function renamed, custom HAL. */
#define TLC2543_HAL_CUSTOM 1
#define tlc2543_init broken_init
#define tlc2543_cycle broken_cycle
#define tlc2543_scan broken_scan
#define tlc2543_self_test_codes broken_self_test_codes
#define tlc2543_self_test broken_self_test
#define tlc2543_power_down broken_power_down
#define tlc2543_signed broken_signed
#define tlc2543_clocks broken_clocks

static int latched_dout;

#define TLC2543_CS(d, v) ((d)->hal->set_cs((d)->hal->ctx, (v)))
#define TLC2543_DIN(d, v) ((d)->hal->set_din((d)->hal->ctx, (v)))
#define TLC2543_EOC(d) ((d)->hal->get_eoc((d)->hal->ctx))
#define TLC2543_DELAY_NS(d, ns) ((d)->hal->delay_ns((d)->hal->ctx, (ns)))
/* BROKEN: DATA OUT is latched the moment the clock falls */
#define TLC2543_CLOCK(d, v)                                                   \
    ((d)->hal->set_clock((d)->hal->ctx, (v)),                                 \
     (void)((v) ? 0 : (latched_dout = (d)->hal->get_dout((d)->hal->ctx))))
#define TLC2543_DOUT(d) (latched_dout)

#include "../src/tlc2543.c"
#include "tlc2543_model.h"

int main(void)
{
    static tlc2543m model;
    static tlc2543 adc;
    static const uint8_t xyz[3] = {0, 1, 2};
    uint16_t codes[3];

    CHECK_EQ_INT(tlc2543m_init(&model, 5.0, 0.0, 0xA5Au), ATT_OK);
    CHECK_EQ_INT(broken_init(&adc, &model.hal, 0), ATT_OK);
    (void)broken_scan(&adc, xyz, 3, codes, 0);
    CHECK_EQ_INT(model.violation, TLC2543M_V_DOUT_EARLY);
    CHECK(model.violation_t > 0);
    return ATT_TEST_REPORT();
}
