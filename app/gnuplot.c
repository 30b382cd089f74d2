/* gnuplot as a helper process (gnuplot.h): fork, a pipe for its stdin, exec
 * from PATH as popen's shell would. */
#define _GNU_SOURCE /* pipe2 */
#include "app/gnuplot.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include "app/outguard.h"

bool gnuplot_open(struct gnuplot *g, bool quiet) {
  g->in = NULL;
  g->pid = -1;
  int fd[2];
  if (pipe2(fd, O_CLOEXEC) != 0) return false;
  const pid_t parent = getpid();
  /* Registered before it runs: a signal from here on finds it. */
  outguard_hold();
  pid_t pid = fork();
  if (pid == 0) {
    /* The child: a parent that died before the setting took effect is
     * caught by the pid check. */
    if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent) _exit(127);
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    signal(SIGHUP, SIG_DFL);
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, NULL);
    int null = open("/dev/null", O_WRONLY);
    if (dup2(fd[0], 0) < 0 || null < 0 || dup2(null, 1) < 0 || (quiet && dup2(null, 2) < 0))
      _exit(127);
    execlp("gnuplot", "gnuplot", (char *)NULL);
    _exit(127);
  }
  close(fd[0]);
  if (pid > 0) outguard_helper(pid);
  outguard_release();
  if (pid < 0 || !(g->in = fdopen(fd[1], "w"))) {
    close(fd[1]);
    if (pid > 0) {
      kill(pid, SIGKILL);
      g->pid = pid;
      gnuplot_close(g);
    }
    return false;
  }
  g->pid = pid;
  return true;
}

bool gnuplot_close(struct gnuplot *g) {
  if (g->in) fclose(g->in); /* gnuplot reads the end of its script */
  g->in = NULL;
  if (g->pid <= 0) return false;
  /* Wait without reaping, so that until it is forgotten below the pid cannot
   * name another process for the signal handler. */
  siginfo_t info;
  while (waitid(P_PID, (id_t)g->pid, &info, WEXITED | WNOWAIT) != 0 && errno == EINTR) {
  }
  outguard_hold();
  outguard_helper_done(g->pid);
  int status = 0;
  bool ok = waitpid(g->pid, &status, 0) == g->pid && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  outguard_release();
  g->pid = -1;
  return ok;
}
