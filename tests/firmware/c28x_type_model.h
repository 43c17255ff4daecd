/*
 * c28x_type_model.h -- forced include (-include) for compiling the
 * tms320f28377 project's C on the host under the C28x type rules of
 * docs/targets.md, together with -DMPC_C28X_TYPE_MODEL and the strict
 * -Werror flags:
 *   - the fixed-width types the sources may use have their C28x sizes in
 *     bits (float 32, uint16_t 16, int32_t/uint32_t 32, uint64_t 64);
 *   - `double`, `int8_t` and `uint8_t` do not exist on the C28x path: they
 *     are poisoned after the standard headers, so any use is a compile error;
 *   - float expressions are evaluated in float (FLT_EVAL_METHOD == 0).
 * What the host cannot model: CHAR_BIT 16 and 16-bit int.  The sources keep
 * record layouts checked in bits (board.c) and use no byte pointers into
 * records; the test also greps for byte-pointer casts.
 */
#ifndef C28X_TYPE_MODEL_H
#define C28X_TYPE_MODEL_H

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define C28X_MODEL_CHECK(name, cond) typedef int name[(cond) ? 1 : -1]
C28X_MODEL_CHECK(c28x_model_float, sizeof(float) * CHAR_BIT == 32);
C28X_MODEL_CHECK(c28x_model_u16, sizeof(uint16_t) * CHAR_BIT == 16);
C28X_MODEL_CHECK(c28x_model_i32, sizeof(int32_t) * CHAR_BIT == 32);
C28X_MODEL_CHECK(c28x_model_u32, sizeof(uint32_t) * CHAR_BIT == 32);
C28X_MODEL_CHECK(c28x_model_u64, sizeof(uint64_t) * CHAR_BIT == 64);
C28X_MODEL_CHECK(c28x_model_eval, FLT_EVAL_METHOD == 0);

#pragma GCC poison double int8_t uint8_t

#endif /* C28X_TYPE_MODEL_H */
