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

void out_uint(uint64_t v) {
  char digits[21];
  int n = 0;
  do {
    digits[n++] = (char)('0' + (int)(v % 10u));
    v /= 10u;
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
    digits[i] = (char)('0' + (int)(v % 10u));
    v /= 10u;
  }
  for (int i = 0; i < width; ++i) out_char(digits[i]);
}

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
