/* Buffered text output and a tiny number printer, on top of out_sink() (no
 * printf: newlib's stdio would bring its heap-using buffers along). */
#include "out.h"

/* line buffer: one trap per line instead of per call */
static char out_buf[128];
static unsigned out_len;

void out_flush(void) {
  if (out_len == 0) return;
  out_buf[out_len] = '\0';
  out_sink(out_buf);
  out_len = 0;
}

void out_char(char c) {
  out_buf[out_len++] = c;
  if (c == '\n' || out_len == sizeof out_buf - 1) out_flush();
}

void out_str(const char *s) {
  while (*s) out_char(*s++);
}

uint64_t out_udiv64(uint64_t n, uint32_t d, uint32_t *rem) {
  /* shift and subtract: no __aeabi_uldivmod (libgcc's 64-bit division, 0.7 KB) */
  uint64_t q = 0, r = 0;
  for (int i = 63; i >= 0; --i) {
    r = (r << 1) | ((n >> i) & 1u);
    if (r >= d) {
      r -= d;
      q |= (uint64_t)1 << i;
    }
  }
  if (rem) *rem = (uint32_t)r;
  return q;
}

void out_uint(uint64_t v) {
  char digits[21];
  int n = 0;
  do {
    uint32_t r;
    v = out_udiv64(v, 10u, &r);
    digits[n++] = (char)('0' + (int)r);
  } while (v != 0);
  while (n > 0) out_char(digits[--n]);
}

void out_int(int64_t v) {
  if (v < 0) {
    out_char('-');
    out_uint((uint64_t)0 - (uint64_t)v);
  } else {
    out_uint((uint64_t)v);
  }
}

void out_hex(uint32_t v) {
  static const char hex[] = "0123456789abcdef";
  out_str("0x");
  for (int shift = 28; shift >= 0; shift -= 4) out_char(hex[(v >> shift) & 0xfu]);
}

static void out_digits(uint64_t v, int width) {
  /* v in exactly `width` digits, zero-padded */
  char digits[20];
  for (int i = width - 1; i >= 0; --i) {
    uint32_t r;
    v = out_udiv64(v, 10u, &r);
    digits[i] = (char)('0' + (int)r);
  }
  for (int i = 0; i < width; ++i) out_char(digits[i]);
}

#if MCU_PRINT_FLOAT
/* Float images (MCU_PRINT_FLOAT, firmware_core/mcu/CMakeLists.txt): every value is a float,
 * printed by integer arithmetic on its bits (fixed point exactly, rounded half up like the
 * double printer), so the image links no software double multiply or divide. Scientific
 * notation (|v| >= 1e9 or too small for the decimals) to float's precision: at most 8
 * digits after the point, the rest zeros. */
#include <string.h>

void out_real(double value, int decimals) {
  const float v = (float)value;
  uint32_t bits;
  memcpy(&bits, &v, sizeof bits);
  if ((bits & 0x7fffffffu) > 0x7f800000u) {
    out_str("nan");
    return;
  }
  if (bits >> 31) out_char('-');
  bits &= 0x7fffffffu;
  if (bits == 0x7f800000u) {
    out_str("inf");
    return;
  }
  if (decimals < 0) decimals = 0;
  if (decimals > 15) decimals = 15;
  float a;
  memcpy(&a, &bits, sizeof a);
  float scale = 1;
  for (int i = 0; i < decimals; ++i) scale *= 10;
  if (a >= 1e9f || (a != 0 && a * scale < 0.5f)) {
    int exp10 = 0;
    while (a >= 10) {
      a /= 10;
      ++exp10;
    }
    while (a < 1) {
      a *= 10;
      --exp10;
    }
    const int shown = decimals > 8 ? 8 : decimals;
    uint32_t unit = 1;
    for (int i = 0; i < shown; ++i) unit *= 10u;
    uint32_t m = (uint32_t)(a * (float)unit + 0.5f);
    if (m >= 10u * unit) { /* rounding carried into a new digit */
      m /= 10u;
      ++exp10;
    }
    out_uint(m / unit);
    if (decimals > 0) {
      out_char('.');
      out_digits(m % unit, shown);
      for (int i = shown; i < decimals; ++i) out_char('0');
    }
    out_char('e');
    out_char(exp10 < 0 ? '-' : '+');
    if (exp10 < 0) exp10 = -exp10;
    out_digits((uint64_t)exp10, exp10 >= 100 ? 3 : 2);
    return;
  }
  /* fixed: a = m 2^-k (a < 1e9: the integer part fits in 32 bits); the fraction's digits
   * by multiplying by 10 in 64 bits (k <= 60: lower bits, below 1e-18, are dropped) */
  int e = (int)(bits >> 23);
  uint32_t m = bits & 0x7fffffu;
  if (e) m |= 0x800000u;
  else e = 1;
  int k = 150 - e;
  uint32_t ip;
  uint64_t frac;
  if (k <= 0) {
    ip = m << -k;
    frac = 0;
    k = 0;
  } else {
    ip = k < 32 ? m >> k : 0;
    if (k > 60) {
      frac = k - 60 < 32 ? m >> (k - 60) : 0;
      k = 60;
    } else {
      frac = m & (((uint64_t)1 << k) - 1);
    }
  }
  char digits[15];
  for (int i = 0; i < decimals; ++i) {
    frac *= 10u;
    digits[i] = (char)('0' + (int)(frac >> k));
    frac &= ((uint64_t)1 << k) - 1;
  }
  if (k > 0 && (frac >> (k - 1))) { /* half up, the carry through the digits */
    int i = decimals - 1;
    while (i >= 0 && digits[i] == '9') digits[i--] = '0';
    if (i >= 0) ++digits[i];
    else ++ip;
  }
  out_uint(ip);
  if (decimals > 0) {
    out_char('.');
    for (int i = 0; i < decimals; ++i) out_char(digits[i]);
  }
}
#else
void out_real(double v, int decimals) {
  if (v != v) {
    out_str("nan");
    return;
  }
  if (v < 0 || (v == 0 && 1.0 / v < 0)) {
    out_char('-');
    v = -v;
  }
  if (v > 1.7976931348623157e308) {
    out_str("inf");
    return;
  }
  if (decimals < 0) decimals = 0;
  if (decimals > 15) decimals = 15;
  uint64_t scale = 1;
  for (int i = 0; i < decimals; ++i) scale *= 10u;

  if (v >= 1e9 || (v != 0 && v * (double)scale < 0.5)) {
    /* scientific: d.ddd...e+XX with `decimals` digits after the point */
    int exp10 = 0;
    while (v >= 10.0) {
      v /= 10.0;
      ++exp10;
    }
    while (v < 1.0) {
      v *= 10.0;
      --exp10;
    }
    uint64_t m = (uint64_t)(v * (double)scale + 0.5);
    if (m >= 10u * scale) { /* rounding carried into a new digit */
      m /= 10u;
      ++exp10;
    }
    out_uint(m / scale);
    if (decimals > 0) {
      out_char('.');
      out_digits(m % scale, decimals);
    }
    out_char('e');
    out_char(exp10 < 0 ? '-' : '+');
    if (exp10 < 0) exp10 = -exp10;
    out_digits((uint64_t)exp10, exp10 >= 100 ? 3 : 2);
    return;
  }
  /* fixed: v < 1e9, so v * 10^15 < 1e24 would overflow; split the integer part */
  uint64_t ip = (uint64_t)v;
  double frac = v - (double)ip;
  uint64_t fp = (uint64_t)(frac * (double)scale + 0.5);
  if (fp >= scale) {
    fp -= scale;
    ++ip;
  }
  out_uint(ip);
  if (decimals > 0) {
    out_char('.');
    out_digits(fp, decimals);
  }
}
#endif
