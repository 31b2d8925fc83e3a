/* Link-time proof that the C interface has no reachable panic: every
 * function is called with inputs the compiler cannot see, and the library is
 * built with its `panic-check` feature, whose panic handler calls a function
 * that exists nowhere. Linked by c/metal/run, never run.
 */
#include <stdint.h>
#include "pftrack.h"

static pftrack_tracker tracker;
static volatile uint8_t input[160 * 120 * 2];
static volatile float sink;

int firmware_main(int argc, char **argv) {
    (void)argv;
    pftrack_config config;
    if (input[15] & 1) pftrack_config_fast(&config);
    else pftrack_config_default(&config);
    config.base = input[16];
    config.lost_below = input[0] / 255.0f;
    config.correlation = input[1];
    pftrack_create(&tracker, argc > 0 ? sizeof tracker : (size_t)input[2], &config, input[3]);
    pftrack_frame frame = {(const uint8_t *)input, sizeof input, input[4], input[5], input[6], input[7]};
    pftrack_box box = {input[8], input[9], input[10], input[11]};
    pftrack_estimate est;
    if (input[12] & 1) pftrack_search(&tracker, &frame, box);
    else pftrack_init(&tracker, &frame, box, &est);
    for (;;) {
        pftrack_step(&tracker, &frame, &est);
        char message[64];
        sink = est.confidence + (float)pftrack_last_error(&tracker, message, input[13]) + pftrack_error_name(input[14])[0];
    }
}
