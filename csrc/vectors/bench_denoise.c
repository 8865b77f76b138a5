/*
 * Instruction-count harness for bench/denoise.py: feeds N samples of one
 * axis to the wavelet denoiser one att_wden_push() call at a time, as a
 * receiver thread would. Run under `qemu-arm -cpu ti925t -singlestep -d
 * nochain,exec` (toolchain/qemu_count.py) with two values of N; the
 * difference divided by the difference of N is the cost per sample (with
 * both N = block + k·hop, every window in between is counted whole). The
 * samples come from a precomputed table (start-up cancels out), indexed
 * with a mask so that the loop adds a few instructions only.
 *
 *   bench_denoise WAVELET MODE LEVELS BLOCK EDGE_START EDGE_END N
 *     WAVELET = haar|db2|db4, MODE = soft|hard
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "attitude/attitude.h"

#define TABLE 256
#define NMAX  1024

static att_real ring[NMAX], scratch[2 * NMAX], out[NMAX], table[TABLE];

int main(int argc, char **argv)
{
    static const char *wavelets[] = { "haar", "db2", "db4" };
    att_wden_config cfg;
    att_wden s;
    unsigned long n, i, outputs = 0, lcg = 1u;
    int w, r;
    if (argc != 8)
        return 2;
    for (w = 0; w < 3; w++)
        if (strcmp(argv[1], wavelets[w]) == 0)
            break;
    att_wden_config_default(&cfg);
    cfg.wavelet = w;
    cfg.mode = strcmp(argv[2], "hard") == 0 ? ATT_WDEN_HARD : ATT_WDEN_SOFT;
    cfg.levels = (unsigned int)strtoul(argv[3], NULL, 10);
    cfg.block = (size_t)strtoul(argv[4], NULL, 10);
    cfg.edge_start = (size_t)strtoul(argv[5], NULL, 10);
    cfg.edge_end = (size_t)strtoul(argv[6], NULL, 10);
    n = strtoul(argv[7], NULL, 10);
    if (cfg.block > NMAX || att_wden_init(&s, &cfg, ring, NMAX, scratch, 2 * NMAX) != ATT_OK)
        return 3;
    for (i = 0; i < TABLE; i++) { /* a gyro at rest: 0.01 rad/s of bias, ±1e-3 rad/s of noise */
        lcg = (lcg * 1664525u + 1013904223u) & 0xFFFFFFFFu;
        table[i] = (att_real)(0.01 + 1e-3 * ((double)lcg / 2147483648.0 - 1.0));
    }
    for (i = 0; i < n; i++) {
        r = att_wden_push(&s, table[i & (TABLE - 1)], out);
        if (r < 0)
            return 4;
        outputs += (unsigned long)r;
    }
    printf("%lu outputs, %lu windows\n", outputs, s.windows);
    return 0;
}
