/* Never calls s51_exit: the harness must time out, not hang. */
#include "s51_sif.h"

volatile unsigned char spin;

void main(void)
{
    s51_puts("spinning\n");
    for (;;) {
        spin++;
    }
}
