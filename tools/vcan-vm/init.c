/*
 * PID 1 of the throwaway vcan VM (see README.md).
 *
 * The kernel runs this from the initramfs. It loads the few modules the
 * initramfs carries (virtio, 9p, virtio_console; list in /modules.list, in
 * dependency order), mounts the host's / (9p tag "hostroot") and makes it the
 * root, mounts the pseudo file systems, then runs stage 2 (a bash script in
 * the per-run directory on the host, $LEGSIM_RUNDIR, given on the kernel
 * command line) and reboots, which ends QEMU (-no-reboot).
 *
 * Static so that it needs nothing from the initramfs but itself; built by
 * tools/vcan-vm/run with the host's gcc -static.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/reboot.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define NEWROOT "/hostroot"

static void say(const char *fmt, ...)
{
	va_list ap;
	fputs("legsim-init: ", stderr);
	va_start(ap, fmt);
	vfprintf(stderr, fmt, ap);
	va_end(ap);
	fputc('\n', stderr);
}

/* No status file gets written, so the host reports a VM failure with the console. */
static void __attribute__((noreturn)) die(const char *fmt, ...)
{
	va_list ap;
	fputs("legsim-init: FATAL: ", stderr);
	va_start(ap, fmt);
	vfprintf(stderr, fmt, ap);
	va_end(ap);
	fprintf(stderr, " (errno %d: %s)\n", errno, strerror(errno));
	sync();
	reboot(RB_AUTOBOOT);
	for (;;)
		pause();
}

static void mnt(const char *src, const char *dst, const char *type,
		unsigned long flags, const char *opts)
{
	mkdir(dst, 0755); /* usually exists already */
	if (mount(src, dst, type, flags, opts) != 0)
		die("mount %s on %s (%s)", src, dst, type);
}

static void load_modules(void)
{
	FILE *f = fopen("/modules.list", "r");
	char path[512];

	if (!f)
		die("open /modules.list");
	while (fgets(path, sizeof path, f)) {
		path[strcspn(path, "\n")] = 0;
		if (!path[0])
			continue;
		int fd = open(path, O_RDONLY | O_CLOEXEC);
		if (fd < 0)
			die("open %s", path);
		if (syscall(SYS_finit_module, fd, "", 0) != 0 && errno != EEXIST)
			die("finit_module %s", path);
		close(fd);
	}
	fclose(f);
}

/* virtio probing is synchronous at module load, but give the 9p channel a
 * moment anyway instead of failing on the first ENOENT. */
static void mount_hostroot(void)
{
	/* cache=loose: much faster program start-up; the share is only read
	 * coherently for files the host does not change while the VM runs. */
	const char *cache = getenv("LEGSIM_9P_CACHE");
	char opts[128];
	snprintf(opts, sizeof opts, "trans=virtio,version=9p2000.L,msize=512000,cache=%s",
		 cache && *cache ? cache : "loose");
	mkdir(NEWROOT, 0755);
	for (int i = 0; i < 200; i++) {
		if (mount("hostroot", NEWROOT, "9p", 0, opts) == 0)
			return;
		if (errno != ENOENT && errno != ENODEV)
			break;
		nanosleep(&(struct timespec){0, 10 * 1000 * 1000}, NULL);
	}
	die("mount 9p hostroot");
}

int main(void)
{
	const char *rundir = getenv("LEGSIM_RUNDIR");
	char stage2[4096];

	mnt("devtmpfs", "/dev", "devtmpfs", 0, NULL);
	int fd = open("/dev/console", O_RDWR);
	if (fd >= 0) {
		dup2(fd, 1);
		dup2(fd, 2);
		if (fd > 2)
			close(fd);
	}
	fd = open("/dev/null", O_RDONLY);
	if (fd >= 0 && fd != 0) {
		dup2(fd, 0);
		close(fd);
	}
	if (!rundir || rundir[0] != '/')
		die("LEGSIM_RUNDIR missing from the kernel command line");

	load_modules();
	mount_hostroot();

	/* The guest's own pseudo file systems over the host's ones in the share. */
	mnt("proc", NEWROOT "/proc", "proc", MS_NOSUID | MS_NODEV | MS_NOEXEC, NULL);
	mnt("sysfs", NEWROOT "/sys", "sysfs", MS_NOSUID | MS_NODEV | MS_NOEXEC, NULL);
	mnt("devtmpfs", NEWROOT "/dev", "devtmpfs", MS_NOSUID, "mode=0755");
	mnt("devpts", NEWROOT "/dev/pts", "devpts", MS_NOSUID | MS_NOEXEC, "gid=5,mode=620,ptmxmode=666");
	mnt("tmpfs", NEWROOT "/dev/shm", "tmpfs", MS_NOSUID | MS_NODEV, "mode=1777");
	mnt("tmpfs", NEWROOT "/run", "tmpfs", MS_NOSUID | MS_NODEV, "mode=0755");

	/* initramfs cannot be pivot_root'ed: move the new root over / and chroot. */
	if (chdir(NEWROOT) != 0 || mount(".", "/", NULL, MS_MOVE, NULL) != 0 ||
	    chroot(".") != 0 || chdir("/") != 0)
		die("switch to the 9p root");

	snprintf(stage2, sizeof stage2, "%s/stage2.sh", rundir);
	pid_t child = fork();
	if (child < 0)
		die("fork");
	if (child == 0) {
		char *argv[] = {"/bin/bash", stage2, (char *)rundir, NULL};
		char *envp[] = {"PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin",
				"HOME=/", "LANG=C.UTF-8", NULL};
		execve(argv[0], argv, envp);
		die("exec /bin/bash %s", stage2);
	}
	/* As PID 1, also reap whatever stage 2 leaves orphaned. */
	for (;;) {
		int st;
		pid_t p = wait(&st);
		if (p == child) {
			if (!WIFEXITED(st) || WEXITSTATUS(st) != 0)
				say("stage 2 ended with status 0x%x", st);
			break;
		}
		if (p < 0 && errno == ECHILD)
			break;
	}
	sync();
	reboot(RB_AUTOBOOT);
	die("reboot");
}
