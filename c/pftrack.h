/* pftrack: a colour particle-filter object tracker for small ARM devices, from C. */

#ifndef PFTRACK_H
#define PFTRACK_H

/* Generated from c/src/lib.rs by cbindgen (c/header); do not edit. */

#include <stddef.h>
#include <stdint.h>

// Particles of every tracker made through this interface.
#define PFTRACK_PARTICLES 100

// Success.
#define PFTRACK_OK 0

// A pointer argument was null.
#define PFTRACK_ERR_NULL -1

// The storage size the caller gave is not this library's: the header and
// the library do not match.
#define PFTRACK_ERR_STORAGE -2

// The storage does not hold a tracker made by [`pftrack_create`].
#define PFTRACK_ERR_NOT_CREATED -3

// The frame's pixel format code is not one of `PFTRACK_FORMAT_*`.
#define PFTRACK_ERR_FORMAT -4

// The frame does not fit its buffer (sizes, stride, planes).
#define PFTRACK_ERR_FRAME -5

// A configuration value is NaN, out of range, or asks for a technique this
// build leaves out.
#define PFTRACK_ERR_CONFIG -6

// The box is empty, not finite, or outside the frame.
#define PFTRACK_ERR_BOX -7

// [`pftrack_step`] before [`pftrack_init`] or [`pftrack_search`].
#define PFTRACK_ERR_NOT_INITIALISED -8

// The frame's size differs from the one the tracker was initialised on.
#define PFTRACK_ERR_FRAME_SIZE_CHANGED -9

// 16-bit RGB 5:6:5, little-endian.
#define PFTRACK_FORMAT_RGB565 1

// 24-bit RGB, bytes R, G, B.
#define PFTRACK_FORMAT_RGB888 2

// YUV 4:2:2 packed as Y0 U Y1 V (YUYV).
#define PFTRACK_FORMAT_YUV422 3

// 8-bit luminance.
#define PFTRACK_FORMAT_GRAY8 4

// Planar YUV 4:2:0: Y plane, then U, then V, in one buffer.
#define PFTRACK_FORMAT_I420 5

// Semi-planar YUV 4:2:0: Y plane, then interleaved U, V, in one buffer.
#define PFTRACK_FORMAT_NV12 6

// `pftrack_config.base`: the other fields apply over the default
// configuration (both correlation filters, a lost target looked for where
// it was lost: the most accurate).
#define PFTRACK_BASE_DEFAULT 0

// `pftrack_config.base`: the other fields apply over the configuration for
// boards that need the frame rate (the grey-level correlation filter
// alone, a lost target looked for over the frame).
#define PFTRACK_BASE_FAST 1

// `pftrack_config.redetect`: a missed target is looked for only where the
// particles go.
#define PFTRACK_REDETECT_OFF 0

// `pftrack_config.redetect`: also at the places near its last one whose
// colours stand out as its own, after a miss while its motion is unknown
// (no step has found it since it was learnt) or while it moves more than
// half its size a frame.
#define PFTRACK_REDETECT_NEAR 1

// `pftrack_config.redetect`: near, and over the whole frame while lost.
#define PFTRACK_REDETECT_FRAME 2

// The tracker searches for its target.
#define PFTRACK_STATE_SEARCHING 0

// The tracker follows its target.
#define PFTRACK_STATE_TRACKING 1

// The target is lost; the tracker searches for it again.
#define PFTRACK_STATE_LOST 2

// Nothing happened this step.
#define PFTRACK_EVENT_NONE 0

// The tracker was initialised on a box.
#define PFTRACK_EVENT_INITIALISED 1

// A searched-for target was found.
#define PFTRACK_EVENT_ACQUIRED 2

// The tracked target was lost.
#define PFTRACK_EVENT_LOST_TARGET 3

// A lost target was found again.
#define PFTRACK_EVENT_REACQUIRED 4

#if defined(__LP64__)
// 64-bit words of a [`pftrack_tracker`] on a 64-bit target.
#define PFTRACK_TRACKER_WORDS 4789
#endif

#if !defined(__LP64__)
// 64-bit words of a [`pftrack_tracker`] on a 32-bit target.
#define PFTRACK_TRACKER_WORDS 4781
#endif

// Bytes of a [`pftrack_tracker`].
#define PFTRACK_TRACKER_BYTES (PFTRACK_TRACKER_WORDS * 8)

// Alignment of a [`pftrack_tracker`], in bytes.
#define PFTRACK_TRACKER_ALIGN 8

// The settings a C caller sets; the rest are those of the configuration
// `base` names. Fill it with [`pftrack_config_default`] or
// [`pftrack_config_fast`], then change fields.
typedef struct {
  // The configuration the other fields apply over: `PFTRACK_BASE_DEFAULT`
  // or `PFTRACK_BASE_FAST`.
  uint8_t base;
  // A tracking frame whose confidence is below this is a miss, in `[0, 1]`.
  float lost_below;
  // A searched-for or lost target is found above this, in `[0, 1]`.
  float found_above;
  // Model adaptation rate, in `[0, 1]`.
  float alpha;
  // Consecutive misses after which a tracked target is lost (1 to 1000).
  uint16_t lost_after;
  // 1: the grey-level correlation filter beside colour; 0: without it.
  uint8_t correlation;
  // 1: a box that moves with its surroundings counts as a miss; 0: off.
  uint8_t scene_motion;
  // Where a missed target is looked for beyond the particles' reach:
  // `PFTRACK_REDETECT_OFF`, `PFTRACK_REDETECT_NEAR` (the default) or
  // `PFTRACK_REDETECT_FRAME`.
  uint8_t redetect;
  // The share of the hypotheses observed on a frame after one confidently
  // on the target, in `(0, 1]`; 1 observes all of them (fewer is faster,
  // and a little less accurate).
  float sure_share;
} pftrack_config;

// Storage for one tracker. Declare one per target (a `static` where the
// stack is small), pass its address and `sizeof` to [`pftrack_create`],
// then its address to every other call. Its bytes are the library's.
typedef struct {
  // The library's bytes: not to be read or written by the caller.
  uint64_t opaque[PFTRACK_TRACKER_WORDS];
} pftrack_tracker;

// One frame as a camera or decoder wrote it: `len` bytes at `data`, rows
// `stride` bytes apart, in format `format` (`PFTRACK_FORMAT_*`); the
// planar formats' chroma planes follow the luma plane in the same buffer.
typedef struct {
  // The first byte of the first row.
  const uint8_t *data;
  // Bytes readable at `data`.
  size_t len;
  // Width in pixels.
  uint32_t width;
  // Height in pixels.
  uint32_t height;
  // Bytes from one row's start to the next's.
  uint32_t stride;
  // One of `PFTRACK_FORMAT_*`.
  uint32_t format;
} pftrack_frame;

// A box: left, top, width, height in pixels.
typedef struct {
  // Left edge.
  float x;
  // Top edge.
  float y;
  // Width.
  float w;
  // Height.
  float h;
} pftrack_box;

// What a step found.
typedef struct {
  // The estimated box.
  pftrack_box bbox;
  // The probability that the estimate is on the target, in `[0, 1]`:
  // what a controller should threshold.
  float confidence;
  // One of `PFTRACK_STATE_*`.
  uint32_t state;
  // One of `PFTRACK_EVENT_*`.
  uint32_t event;
} pftrack_estimate;

#ifdef __cplusplus
extern "C" {
#endif // __cplusplus

// Fills `out` with the default settings (`Config::default()`).
//
// # Safety
// `out` is null or points to a writable `pftrack_config`.
int32_t pftrack_config_default(pftrack_config *out);

// Fills `out` with the settings for boards that need the frame rate
// (`Config::fast()`).
//
// # Safety
// `out` is null or points to a writable `pftrack_config`.
int32_t pftrack_config_fast(pftrack_config *out);

// Makes a tracker in `t` with settings `config` and random seed `seed`
// (the same seed and frames give the same track, bit for bit, on every
// target). `size` is `sizeof(pftrack_tracker)` as the caller's header
// says it. Any earlier tracker in `t` is forgotten.
//
// # Safety
// `t` is null or points to a writable `pftrack_tracker` not used elsewhere
// during the call; `config` is null or points to a `pftrack_config`.
int32_t pftrack_create(pftrack_tracker *t,
                       size_t size,
                       const pftrack_config *config,
                       uint64_t seed);

// Learns the target in `bbox` of `frame` and tracks it from there; call it
// again at any time to re-initialise. Writes the first estimate to `out`
// (if not null).
//
// # Safety
// `t` as for [`pftrack_create`]; `frame` null or pointing to a
// `pftrack_frame` whose `data` is readable for `len` bytes; `out` null or
// writable.
int32_t pftrack_init(pftrack_tracker *t,
                     const pftrack_frame *frame,
                     pftrack_box bbox,
                     pftrack_estimate *out);

// Learns the target in `bbox` of `frame`, then searches for it in the
// frames that follow.
//
// # Safety
// As for [`pftrack_init`].
int32_t pftrack_search(pftrack_tracker *t, const pftrack_frame *frame, pftrack_box bbox);

// Tracks one frame and writes the estimate to `out` (if not null).
//
// # Safety
// As for [`pftrack_init`].
int32_t pftrack_step(pftrack_tracker *t, const pftrack_frame *frame, pftrack_estimate *out);

// The name of a code, as a static NUL-terminated string.
const char *pftrack_error_name(int32_t code);

// Writes the message of the last error of the tracker in `t` (which field,
// which box, which size), NUL-terminated and cut to `len` bytes, into
// `buf`; returns the message's length without the NUL (0 if the last call
// succeeded or `t` holds no tracker).
//
// # Safety
// `t` as for [`pftrack_create`]; `buf` null or writable for `len` bytes.
size_t pftrack_last_error(pftrack_tracker *t, char *buf, size_t len);

#ifdef __cplusplus
}  // extern "C"
#endif  // __cplusplus

#endif  /* PFTRACK_H */

/* A header that does not match its target fails here; one that does not
   match its library fails pftrack_create's size check (PFTRACK_ERR_STORAGE). */
#ifndef __cplusplus
_Static_assert(sizeof(pftrack_tracker) == PFTRACK_TRACKER_BYTES, "pftrack_tracker size");
_Static_assert(_Alignof(pftrack_tracker) == PFTRACK_TRACKER_ALIGN, "pftrack_tracker alignment");
#endif
