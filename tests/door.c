/* Linked with every object of the renderer and the base library only (CMake
 * target renderer_door): if any renderer file called into the machine, this
 * program would not link. It runs nothing. */
int main(void) { return 0; }
