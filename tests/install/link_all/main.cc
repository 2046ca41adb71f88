// The program of tests/install/link_all/CMakeLists.txt: its content is the libraries linked whole;
// running it runs their static initialisers (the command and stage registries) once.
int main() { return 0; }
