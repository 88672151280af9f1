/* What both work-precision drivers (legsim_wp.c, mujoco_wp.c) do alike: the wall clock,
 * and a span as a whole number of steps. */
#ifndef LEGSIM_WP_COMMON_H
#define LEGSIM_WP_COMMON_H

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* span / h as a whole number of steps; anything else is a usage error (exit 2). */
static int steps_of(const char *who, double span, double h) {
  const double n = span / h;
  const int k = (int)(n + 0.5);
  if (k < 1 || (n - k) > 1e-9 * n || (k - n) > 1e-9 * n) {
    fprintf(stderr, "%s: %g s is not a whole number of steps of %g s\n", who, span, h);
    exit(2);
  }
  return k;
}

#endif
