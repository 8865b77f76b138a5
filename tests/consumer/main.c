/* A program of a libattitude user, built outside the library's tree against
 * an installed copy: through pkg-config (Makefile) or CMake's find_package
 * (CMakeLists.txt). tests/test_consumer.py builds and runs it on the host
 * and on armv4t under qemu-arm. It prints the size of att_real (8, or 4 in
 * a float build: proves ATT_REAL_F32 reached the compile) and the attitude
 * after 0.03 rad about z: q = [cos 0.015, 0, 0, sin 0.015]. */
#include <stdio.h>

#include "attitude/attitude.h"

int main(void)
{
    const att_real d[9] = { 0, 0, 0.01, 0, 0, 0.01, 0, 0, 0.01 };
    att_real q[4];
    att_integ s;
    size_t n = 0;
    if (att_integ_init(&s, ATT_METHOD_RV3, NULL) != ATT_OK || att_integ_batch(&s, d, 3, q, &n, NULL) != ATT_OK
        || n != 1) {
        return 1;
    }
    if (att_real_size() != (int)sizeof(att_real)) {
        return 2; /* the headers and the library disagree on att_real */
    }
    printf("att_real=%d ok=%s q=%.6f %.6f\n", att_real_size(), att_status_str(ATT_OK), (double)q[0],
           (double)q[3]);
    return 0;
}
