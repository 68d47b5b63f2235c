/* A unit's saved state (fmi2_cs.c, fmi3_cs.c): the instance itself, one struct of `size` bytes without pointers
 * besides the callbacks, so saving, restoring and (de)serialising are copies of it and a restored step repeats
 * bit for bit (fmus/README.md).  Each returns 0, or -1 on failure; a deserialised state keeps the callbacks it
 * was saved with (the caller puts the running instance's in). */
#ifndef ICOSIM_STATE_H
#define ICOSIM_STATE_H
#include <stdlib.h>
#include <string.h>

static int state_save(const void *instance, void **state, size_t size) {
    if (*state == NULL) *state = malloc(size);
    if (*state == NULL) return -1;
    memcpy(*state, instance, size);
    return 0;
}

static int state_restore(void *instance, const void *state, size_t size) {
    if (state == NULL) return -1;
    memcpy(instance, state, size);
    return 0;
}

static void state_free(void **state) {
    if (state && *state) { free(*state); *state = NULL; }
}

static int state_serialize(const void *state, void *bytes, size_t nbytes, size_t size) {
    if (nbytes != size) return -1;
    memcpy(bytes, state, size);
    return 0;
}

static int state_deserialize(const void *bytes, size_t nbytes, void **state, size_t size) {
    if (nbytes != size) return -1;
    return state_save(bytes, state, size);
}
#endif
