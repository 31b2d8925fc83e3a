/* Tracks a .pft fixture through the C interface and prints one JSON line
 * per frame, as `track run FIXTURE --box ...` does (frame 1 is the box
 * given; numbers with nine significant digits, which read back as the same
 * float).
 *
 *   track_fixture FIXTURE [SEED [fast]]
 *
 * (`fast`: the configuration for boards that need the frame rate, as
 * `track run --set config=fast`.)
 *
 * The fixture format is in docs/fixtures.md: a 32-byte header, then records
 * of a ground-truth box (4 little-endian floats), 4 bytes, and the frame.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pftrack.h"

/* A `static`: the storage is about 37 KB, more than small stacks hold. */
static pftrack_tracker tracker;

static uint32_t u32_at(const uint8_t *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float f32_at(const uint8_t *p) {
    uint32_t bits = u32_at(p);
    float v;
    memcpy(&v, &bits, sizeof v);
    return v;
}

static const char *state_name(uint32_t s) {
    switch (s) {
    case PFTRACK_STATE_SEARCHING: return "searching";
    case PFTRACK_STATE_TRACKING: return "tracking";
    default: return "lost";
    }
}

static const char *event_json(uint32_t e) {
    switch (e) {
    case PFTRACK_EVENT_INITIALISED: return "\"initialised\"";
    case PFTRACK_EVENT_ACQUIRED: return "\"acquired\"";
    case PFTRACK_EVENT_LOST_TARGET: return "\"lost\"";
    case PFTRACK_EVENT_REACQUIRED: return "\"reacquired\"";
    default: return "null";
    }
}

static void print_line(unsigned frame, const char *state, const char *event, float confidence, pftrack_box b) {
    printf("{\"frame\":%u,\"state\":\"%s\",\"event\":%s,\"confidence\":%.9g,\"box\":[%.9g,%.9g,%.9g,%.9g]}\n",
           frame, state, event, confidence, b.x, b.y, b.w, b.h);
}

static int fail(const char *what, int code) {
    char message[192];
    pftrack_last_error(&tracker, message, sizeof message);
    fprintf(stderr, "%s: %s (%d): %s\n", what, pftrack_error_name(code), code, message);
    return 1;
}

int main(int argc, char **argv) {
    if (argc < 2 || argc > 4 || (argc == 4 && strcmp(argv[3], "fast") != 0)) {
        fprintf(stderr, "usage: %s FIXTURE [SEED [fast]]\n", argv[0]);
        return 2;
    }
    uint64_t seed = argc >= 3 ? strtoull(argv[2], NULL, 10) : 1;
    FILE *f = fopen(argv[1], "rb");
    uint8_t header[32];
    if (!f || fread(header, 1, sizeof header, f) != sizeof header || memcmp(header, "PFTRKFX1", 8) != 0) {
        fprintf(stderr, "%s: not a fixture\n", argv[1]);
        return 1;
    }
    uint32_t format = (uint32_t)header[10] | (uint32_t)header[11] << 8;
    uint32_t width = (uint32_t)header[12] | (uint32_t)header[13] << 8;
    uint32_t height = (uint32_t)header[14] | (uint32_t)header[15] << 8;
    uint32_t stride = u32_at(header + 16);
    uint32_t frames = u32_at(header + 20);
    size_t frame_bytes = (size_t)stride * height;
    if (format == PFTRACK_FORMAT_I420) frame_bytes += 2 * (size_t)(stride / 2) * (height / 2);
    if (format == PFTRACK_FORMAT_NV12) frame_bytes += (size_t)stride * (height / 2);
    uint8_t *record = malloc(20 + frame_bytes);
    if (!record) return 1;

    pftrack_config config;
    if (argc == 4) pftrack_config_fast(&config);
    else pftrack_config_default(&config);
    int code = pftrack_create(&tracker, sizeof tracker, &config, seed);
    if (code != PFTRACK_OK) return fail("create", code);

    for (uint32_t n = 1; n <= frames; n++) {
        if (fread(record, 1, 20 + frame_bytes, f) != 20 + frame_bytes) {
            fprintf(stderr, "%s: frame %u is truncated\n", argv[1], (unsigned)n);
            return 1;
        }
        pftrack_frame frame = {record + 20, frame_bytes, width, height, stride, format};
        pftrack_estimate est;
        if (n == 1) {
            pftrack_box box = {f32_at(record), f32_at(record + 4), f32_at(record + 8), f32_at(record + 12)};
            code = pftrack_init(&tracker, &frame, box, &est);
            if (code != PFTRACK_OK) return fail("init", code);
            print_line((unsigned)n, "tracking", "\"initialised\"", 1.0f, box);
        } else {
            code = pftrack_step(&tracker, &frame, &est);
            if (code != PFTRACK_OK) return fail("step", code);
            print_line((unsigned)n, state_name(est.state), event_json(est.event), est.confidence, est.bbox);
        }
    }
    free(record);
    fclose(f);
    return 0;
}
