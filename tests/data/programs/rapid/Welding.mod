%%%
  VERSION:1
  LANGUAGE:ENGLISH
%%%
MODULE Welding
    ! golden RAPID module: declarations, inline targets, MoveL/J/C/AbsJ, tool and work object
    PERS tooldata tGun := [TRUE,[[12.5,-3,245.75],[0.976296,0,0.216440,0]],[2.5,[0,0,120],[1,0,0,0],0.01,0.01,0.01]];
    TASK PERS wobjdata wTable := [FALSE,TRUE,"",[[800,-300,250],[0.707106781,0,0,0.707106781]],[[10,20,0],[1,0,0,0]]];
    PERS wobjdata wFixture := [FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
    CONST robtarget pApproach:=[[100.00,50.00,150.00],[0.00,0.00,1.00,0.00],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pStart:=[[100.0,50.0,2.5],[-4.37114E-08,0.707107,0.707107,-4.37114E-08],[-1,0,-1,1],[9E9,9E9,9E9,9E9,9E9,9E9]];
    LOCAL CONST robtarget pVia := [[150.000, 75.000, 2.500], [0, 0, 1, 0],
                                   [0, -1, 0, 0], [9E+09, 9E+09, 9E+09, 9E+09, 9E+09, 9E+09]];
    VAR robtarget pEnd:=[[200,50,2.5],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pFixture:=[[20,30,40],[0,0.70710678,0.70710678,0],[1,0,1,0],[250.5,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST jointtarget jHome:=[[0,0,0,0,30,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pUnused:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST speeddata vWeld:=[12,500,5000,1000];

    PROC main()
        MoveAbsJ jHome\NoEOffs, v1000, fine, tool0;
        MoveJ pApproach, v1000, z50, tGun\WObj:=wTable;
        MoveL pStart, v200, fine, tGun\WObj:=wTable; ! comment with ; and MoveL
        MoveC pVia, pEnd, v100\V:=12.5, z1, tGun\WObj:=wTable;
        MoveL Offs(pEnd,0,0,50), v500, z10, tGun\WObj:=wTable;
        MoveL RelTool(pStart,0,0,-20), v500, z10, tGun\WObj:=wTable;
        MoveL [[900,0,600],[0.5,-0.5,0.5,0.5],[0,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]], v1000, z10\Z:=7.5, tool0;
        MoveL pFixture, vWeld, z5, tGun \WObj:=wFixture;
        MoveJ \Conc, pApproach, vmax, z100, tGun\WObj:=wTable;
        MoveAbsJ [[10,-20,30,0,45,-90],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]], v500, z20, tool0;
        MoveL CRobT(\Tool:=tGun), v100, fine, tGun;
        WaitTime 0.5;
        TPWrite "done; MoveL p";
    ENDPROC
ENDMODULE
